//! Anderson acceleration of the projected Gauss–Seidel sweep \[not in seed: Anderson's mixing
//! (1965) of a fixed-point iteration, as Walker and Ni (2011) state it, "type II"; applied to
//! the impulses of a contact sweep\].
//!
//! One sweep is a map G from the stacked contact impulses P to the next ones; the solution is
//! its fixed point. Plain sweeps creep toward it where contacts are many and coupled (a load
//! travels one contact per sweep, and redundant points of one face trade impulse slowly).
//! Anderson's step takes the last few iterates x_j and their images G(x_j), with residuals
//! f_j = G(x_j) − x_j, finds the combination of the residual differences that best cancels the
//! newest residual,
//!
//! ```text
//! γ = argmin ‖f_k − ΔF·γ‖,   ΔF = [f_{j+1} − f_j],   ΔG = [G(x_{j+1}) − G(x_j)],
//! ```
//!
//! and proposes x = G(x_k) − ΔG·γ: the image the residuals' linear model says has none. The
//! proposal is projected onto the cones (p_n ≥ 0, ‖p_t‖ ≤ μ p_n) by the caller and judged by
//! the sweep that follows it: a sweep that changes more than the one before the proposal
//! drops the history ([`Anderson::restart`]), so an extrapolation that did not help costs one
//! sweep. The fixed point, and so the law every converged solve obeys, is unchanged: the solve
//! still stops only after a plain sweep that changed no velocity by more than the tolerance.

use super::{Contact, IslandBody, Row, flatten, move_impulses};

/// Largest ridge, relative to the largest diagonal entry of ΔFᵀΔF, added to the normal
/// equations of the mixing least squares: residual differences that are nearly parallel make
/// them singular, and the ridge keeps γ bounded (a smaller step, never a wild one). Default
/// `1e-10`.
pub const MIXING_RIDGE: f64 = 1e-10;

/// Largest impulse component a proposal may hold, as a multiple of the largest of the sweep
/// output it extrapolates from. Default `2`.
pub const MAX_GROWTH: f64 = 2.0;

/// A sweep makes progress when its residual falls below this share of the best before it.
/// Default `0.9`.
pub const PROGRESS: f64 = 0.9;

/// Sweeps without progress ([`PROGRESS`]), per iterate of memory, after which a solve stops
/// accelerating and goes on with plain sweeps: where the sweep's map is not smooth near the
/// solution (contacts trading between sticking and sliding), the linear model of the
/// residuals fails and every proposal is undone, while plain sweeps still creep in. Default
/// `4`.
pub const STALL_SWEEPS_PER_MEMORY: usize = 20;

/// The history of an accelerated solve, in buffers sized once per solve: the last `memory`
/// residual and image differences (a ring: the least squares does not depend on the
/// columns' order), their Gram matrix updated a column at a time, and the newest residual
/// and image.
struct Anderson {
    memory: usize,
    /// Numbers per iterate (three a contact).
    len: usize,
    /// ΔF columns, `memory × len`.
    df: Vec<f64>,
    /// ΔG columns, `memory × len`.
    dg: Vec<f64>,
    /// ΔFᵀΔF, `memory × memory`.
    gram: Vec<f64>,
    /// Columns held (≤ memory), and the slot the next one goes to.
    held: usize,
    next: usize,
    /// The newest residual f_k and image G(x_k); `has_last` once one is recorded.
    last_f: Vec<f64>,
    last_g: Vec<f64>,
    has_last: bool,
    /// Scratch: the residual being recorded, the normal equations' matrix and right side.
    f: Vec<f64>,
    factor: Vec<f64>,
    rhs: Vec<f64>,
}

impl Anderson {
    /// An empty history keeping up to `memory` differences of iterates of `len` numbers.
    fn new(memory: usize, len: usize) -> Self {
        Self {
            memory,
            len,
            df: vec![0.0; memory * len],
            dg: vec![0.0; memory * len],
            gram: vec![0.0; memory * memory],
            held: 0,
            next: 0,
            last_f: vec![0.0; len],
            last_g: vec![0.0; len],
            has_last: false,
            f: vec![0.0; len],
            factor: vec![0.0; memory * memory],
            rhs: vec![0.0; memory],
        }
    }

    /// Forgets every iterate (the next proposal needs two new ones).
    fn restart(&mut self) {
        self.held = 0;
        self.next = 0;
        self.has_last = false;
    }

    /// Records the sweep that took `before` to `after` and writes the accelerated proposal
    /// into `proposal`; returns `false` (and leaves `proposal` alone) while the history holds
    /// a single iterate or the least squares is degenerate.
    fn propose(&mut self, before: &[f64], after: &[f64], proposal: &mut [f64]) -> bool {
        let (n, m) = (self.len, self.memory);
        for ((f, a), b) in self.f.iter_mut().zip(after).zip(before) {
            *f = a - b;
        }
        if self.has_last {
            // The new column: ΔF = f_k − f_{k−1}, ΔG = G(x_k) − G(x_{k−1}).
            let slot = self.next;
            let (df, dg) = (
                &mut self.df[slot * n..(slot + 1) * n],
                &mut self.dg[slot * n..(slot + 1) * n],
            );
            for i in 0..n {
                df[i] = self.f[i] - self.last_f[i];
                dg[i] = after[i] - self.last_g[i];
            }
            self.held = (self.held + 1).min(m);
            self.next = (slot + 1) % m;
            for a in 0..self.held {
                let s = dot(
                    &self.df[a * n..(a + 1) * n],
                    &self.df[slot * n..(slot + 1) * n],
                );
                self.gram[a * m + slot] = s;
                self.gram[slot * m + a] = s;
            }
        }
        self.last_f.copy_from_slice(&self.f);
        self.last_g.copy_from_slice(after);
        self.has_last = true;
        let k = self.held;
        if k == 0 {
            return false;
        }
        // Normal equations (ΔFᵀΔF + ridge) γ = ΔFᵀ f_k over the held columns.
        let scale = (0..k).map(|a| self.gram[a * m + a]).fold(0.0, f64::max);
        if !(scale > 0.0 && scale.is_finite()) {
            return false;
        }
        for a in 0..k {
            for b in 0..k {
                self.factor[a * k + b] = self.gram[a * m + b];
            }
            self.factor[a * k + a] += MIXING_RIDGE * scale;
            self.rhs[a] = dot(&self.df[a * n..(a + 1) * n], &self.f);
        }
        if !cholesky_solve(&mut self.factor[..k * k], &mut self.rhs[..k], k) {
            return false;
        }
        // x = G(x_k) − ΔG·γ.
        proposal.copy_from_slice(after);
        for a in 0..k {
            let g = self.rhs[a];
            for (x, d) in proposal.iter_mut().zip(&self.dg[a * n..(a + 1) * n]) {
                *x -= g * d;
            }
        }
        // An extrapolation along directions the velocities barely see (a light body squeezed
        // between two contacts) can grow impulses without bound while the residual stays
        // small; such a proposal is refused.
        let largest = after.iter().fold(0.0_f64, |m, v| m.max(v.abs()));
        proposal
            .iter()
            .all(|v| v.is_finite() && v.abs() <= MAX_GROWTH * largest)
    }
}

/// Σ aᵢbᵢ.
fn dot(a: &[f64], b: &[f64]) -> f64 {
    a.iter().zip(b).map(|(x, y)| x * y).sum()
}

/// An accelerated solve's state between sweeps: the history, the impulses before and after
/// the last sweep, and the best sweep output so far (an accelerated solve that ends
/// unconverged returns it rather than wherever the last proposal led: a plain sweep's creep
/// is monotone in practice, an extrapolation's path is not).
pub(super) struct Accelerated {
    history: Anderson,
    before: Vec<f64>,
    after: Vec<f64>,
    proposal: Vec<f64>,
    kept: Vec<f64>,
    kept_residual: f64,
    last_residual: f64,
    proposed: bool,
}

impl Accelerated {
    /// Starts from the contacts' impulses after a sweep of residual `residual`.
    pub(super) fn new(memory: usize, contacts: &[Contact], residual: f64) -> Self {
        let len = 3 * contacts.len();
        let mut before = vec![0.0; len];
        flatten(contacts, &mut before);
        Self {
            history: Anderson::new(memory, len),
            kept: before.clone(),
            before,
            after: vec![0.0; len],
            proposal: vec![0.0; len],
            kept_residual: residual,
            last_residual: f64::INFINITY,
            proposed: false,
        }
    }

    /// Forgets the history after the impulses were changed from outside (a direct solve).
    pub(super) fn restart(&mut self, contacts: &[Contact]) {
        self.history.restart();
        flatten(contacts, &mut self.before);
        self.proposed = false;
        self.last_residual = f64::INFINITY;
        self.kept_residual = f64::INFINITY;
    }

    /// Keeps the contacts' impulses if `residual` is the least seen.
    pub(super) fn keep_if_best(&mut self, contacts: &[Contact], residual: f64) {
        if residual < self.kept_residual {
            self.kept_residual = residual;
            flatten(contacts, &mut self.kept);
        }
    }

    /// The residual of the kept sweep output.
    pub(super) fn kept_residual(&self) -> f64 {
        self.kept_residual
    }

    /// Puts the kept sweep output back.
    pub(super) fn restore(
        &self,
        bodies: &mut [IslandBody],
        contacts: &mut [Contact],
        rows: &[Row],
    ) {
        move_impulses(bodies, contacts, rows, &self.kept);
    }

    /// After a sweep of residual `residual`: records it and moves the impulses to the
    /// accelerated proposal if there is one.
    pub(super) fn step(
        &mut self,
        bodies: &mut [IslandBody],
        contacts: &mut [Contact],
        rows: &[Row],
        residual: f64,
    ) {
        if self.proposed && residual > self.last_residual {
            self.history.restart();
        }
        self.last_residual = residual;
        flatten(contacts, &mut self.after);
        if self
            .history
            .propose(&self.before, &self.after, &mut self.proposal)
        {
            move_impulses(bodies, contacts, rows, &self.proposal);
            flatten(contacts, &mut self.before);
            self.proposed = true;
        } else {
            std::mem::swap(&mut self.before, &mut self.after);
            self.proposed = false;
        }
    }
}

/// Solves the symmetric positive definite `m × m` system `a·x = b` in place (`a` row-major,
/// overwritten by its Cholesky factor; `b` by `x`); `false` if a pivot is not positive.
fn cholesky_solve(a: &mut [f64], b: &mut [f64], m: usize) -> bool {
    for j in 0..m {
        let mut d = a[j * m + j];
        for k in 0..j {
            d -= a[j * m + k] * a[j * m + k];
        }
        if d.is_nan() || d <= 0.0 {
            return false;
        }
        let d = d.sqrt();
        a[j * m + j] = d;
        for i in j + 1..m {
            let mut s = a[i * m + j];
            for k in 0..j {
                s -= a[i * m + k] * a[j * m + k];
            }
            a[i * m + j] = s / d;
        }
    }
    for i in 0..m {
        let mut s = b[i];
        for k in 0..i {
            s -= a[i * m + k] * b[k];
        }
        b[i] = s / a[i * m + i];
    }
    for i in (0..m).rev() {
        let mut s = b[i];
        for k in i + 1..m {
            s -= a[k * m + i] * b[k];
        }
        b[i] = s / a[i * m + i];
    }
    true
}
