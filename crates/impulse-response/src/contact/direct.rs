//! A direct solve of the contact problem on the active set Gauss–Seidel found, for islands
//! where Gauss–Seidel converges too slowly (tall stacks: a load travels one contact per sweep).
//!
//! Gauss–Seidel's iterate, even far from converged, usually has the right *active set*: which
//! contacts press (p_n > 0), which of those stick (‖p_t‖ < μ p_n) and which slide (on the
//! cone's rim, in a direction d). On that set the contact problem is linear:
//! - a sticking contact has three unknowns (p_t1, p_t2, p_n) and three equations u = (0, 0,
//!   u_target);
//! - a sliding contact has one unknown p_n, its friction fixed at p_t = μ·p_n·d, and one
//!   equation u_n = u_target;
//! - a contact that does not press has neither.
//!
//! A class also forces part of the change: a contact that does not press drops the impulse
//! it had, a sliding one has its friction put on the rim in its direction. With u = u_now +
//! W·(F + ΔP) (W the island's Delassus matrix, built here column by column from the bodies'
//! mass properties, only between contacts that share a body; F the forced changes, ΔP the
//! unknowns), this is one square linear system, solved by LU with a tiny Tikhonov term
//! ([`REGULARISATION`]) because an interface of four corners has more contact rows than the
//! six relative degrees of freedom of two bodies (the redundant rows make W singular). The
//! result is checked against the laws (p_n ≥ 0, ‖p_t‖ ≤ μ p_n, u_n ≥ u_target where nothing
//! presses); a contact that breaks one changes class and the system is solved again, up to
//! [`MAX_ROUNDS`] times, until a set of classes comes back (a cycle), or until a round's
//! impulses dwarf the iterate's ([`DIVERGED`]: a near-singular or inconsistent system,
//! whose rounds only cost time; on the settling pyramid of 55 such failures were most of the
//! run's wall time). The
//! caller keeps sweeping afterwards, so the laws are Gauss–Seidel's to enforce in the end;
//! the direct solve only brings the iterate next to the solution in one stroke.
//!
//! Cost: W is sparse — a contact couples only to the contacts of its two bodies — and is
//! assembled in compressed columns. Up to [`DENSE_UP_TO`] unknowns (3 per sticking contact)
//! it is factorised dense (O(m³), the least overhead); beyond, by faer's supernodal sparse LU
//! after its fill-reducing column ordering (a stack's W is block-tridiagonal: O(m)), the
//! symbolic analysis kept from the last pattern seen on the thread. It is called only when
//! Gauss–Seidel has not converged after
//! [`super::SolverSettings::direct_after`] sweeps, which in a time-stepping loop means while
//! an island's loads change, not while it rests (its warm start is then already the solution).

use faer::dyn_stack::{MemBuffer, MemStack};
use faer::linalg::lu::partial_pivoting::factor::{lu_in_place, lu_in_place_scratch};
use faer::linalg::lu::partial_pivoting::solve::{solve_in_place_scratch, solve_in_place_with_conj};
use faer::sparse::linalg::SupernodalThreshold;
use faer::sparse::linalg::lu::{LuSymbolicParams, NumericLu, SymbolicLu, factorize_symbolic_lu};
use faer::sparse::{SparseColMat, SymbolicSparseColMat};
use faer::{Conj, Mat, Par};
use glam::{DVec2, DVec3};
use std::cell::RefCell;

use super::{Contact, IslandBody, Row, apply, contact_velocity};
use crate::body::Body;

/// Tikhonov term of the direct solve, relative to W's largest diagonal entry: far below any
/// physical compliance, far above the rounding that makes a redundant system's LU break
/// down. Default `1e-10`.
pub const REGULARISATION: f64 = 1e-10;

/// Systems of up to this many unknowns are solved by a dense LU, larger ones by a sparse LU
/// (faer's supernodal LU with its fill-reducing column ordering). W is sparse — a contact
/// couples only to the contacts of its two bodies — so for a stack (block-tridiagonal W) the
/// sparse LU costs O(m) where the dense one costs O(m³); below this size the dense LU's lower
/// overhead wins. Default `96` (a stack of 8 sticking on four corners each).
pub const DENSE_UP_TO: usize = 96;

/// Most active-set corrections of one direct solve. Default `16`.
pub const MAX_ROUNDS: usize = 16;

/// A round whose impulses exceed this multiple of the largest normal impulse the iterate
/// had ends the direct solve (the system is near-singular or inconsistent, and the classes
/// it flips are noise). Measured on the pyramid of 55 and the dominos: accepted solves
/// never exceeded 21 in any round; failed ones reached 1e5–1e6, mostly in their first round.
/// Default `1e3`.
pub const DIVERGED: f64 = 1e3;

/// Relative slack of the checks of the laws (a normal impulse may be this fraction of the
/// largest one below zero, a friction impulse this fraction outside its cone). Default
/// `1e-9`.
pub const LAW_SLACK: f64 = 1e-9;

/// A sliding contact's friction direction is taken from the slip the solve finds when the two
/// differ by more than the angle of this cosine (about 0.8°). Default `1 − 1e-4`.
pub const SLIDE_DIRECTION_COS: f64 = 1.0 - 1e-4;

#[derive(Clone, Copy, PartialEq)]
enum Class {
    Off,
    Stick,
    Slide(DVec2),
}

impl Class {
    fn unknowns(self) -> usize {
        match self {
            Class::Off => 0,
            Class::Stick => 3,
            Class::Slide(_) => 1,
        }
    }
}

/// Tries to jump to the solution on Gauss–Seidel's active set (or, when that fails other
/// than by diverging in its first round, on the set where every contact sticks); applies the
/// impulse change to the bodies and contacts and returns true when the result keeps the laws
/// (a contact that does not press may not approach faster than `tolerance` below its target),
/// else changes nothing and returns false.
pub(super) fn solve_active_set(
    bodies: &mut [IslandBody],
    contacts: &mut [Contact],
    rows: &[Row],
    tolerance: f64,
) -> bool {
    let n = contacts.len();
    if n == 0 {
        return false;
    }
    let guess: Vec<Class> = contacts
        .iter()
        .map(|c| {
            let p_t = DVec2::new(c.impulse.x, c.impulse.y);
            let cone = c.friction * c.impulse.z;
            if c.impulse.z <= 0.0 {
                Class::Off
            } else if p_t.length() < cone * (1.0 - LAW_SLACK) || p_t.length() == 0.0 {
                Class::Stick
            } else {
                Class::Slide(p_t / p_t.length())
            }
        })
        .collect();
    let w = Couplings::new(bodies, contacts, rows);
    // Gauss–Seidel's classes first; failing those, every contact sticking (an island at
    // rest, whose iterate was too far from converged to tell).
    match solve_from(bodies, contacts, rows, &w, tolerance, guess) {
        Outcome::Accepted => true,
        // The first system's solution already dwarfed the iterate: its targets are ones no
        // rigid motion meets (a loop of contacts, as on the pyramid, where a block's two
        // patches ask its face for different motions), and the all-stick system keeps
        // those targets. Measured with both tried: 82 of the pyramid's 86 failed solves and
        // 60 over the impulse-sim tests diverged at once on both sets, and none of them was
        // saved by the second.
        Outcome::DivergedAtOnce => false,
        Outcome::Failed => {
            solve_from(bodies, contacts, rows, &w, tolerance, vec![Class::Stick; n])
                == Outcome::Accepted
        }
    }
}

/// How [`solve_from`] ended.
#[derive(Clone, Copy, Debug, PartialEq)]
enum Outcome {
    /// The result keeps the laws; its impulses were applied.
    Accepted,
    /// The first round's solution exceeded [`DIVERGED`] times the iterate's impulses.
    DivergedAtOnce,
    /// Any other failure: a later divergence, a cycle of classes, [`MAX_ROUNDS`] spent, or a
    /// system that could not be solved.
    Failed,
}

/// Which contacts an impulse at a contact reaches, and how: W's non-zero blocks.
struct Couplings {
    /// For each contact j: every contact i sharing a moving body with it (ascending), with
    /// i's velocity change (its frame) for a unit impulse along each axis of j's frame.
    responses: Vec<Vec<(usize, [DVec3; 3])>>,
}

impl Couplings {
    fn new(bodies: &[IslandBody], contacts: &[Contact], rows: &[Row]) -> Self {
        // The contacts of each moving body (a fixed body passes no impulse on).
        let mut by_body: Vec<Vec<usize>> = vec![Vec::new(); bodies.len()];
        for (k, c) in contacts.iter().enumerate() {
            for b in [Some(c.body1), c.body2].into_iter().flatten() {
                if !matches!(bodies[b].body, Body::Fixed) {
                    by_body[b].push(k);
                }
            }
        }
        let responses = contacts
            .iter()
            .enumerate()
            .map(|(j, c)| {
                let mut near: Vec<usize> = by_body[c.body1].clone();
                if let Some(b) = c.body2 {
                    near.extend(&by_body[b]);
                }
                near.sort_unstable();
                near.dedup();
                let axes = [DVec3::X, DVec3::Y, DVec3::Z].map(|d| rows[j].frame.to_world(d));
                near.into_iter()
                    .map(|i| (i, axes.map(|p| response(bodies, contacts, rows, i, j, p))))
                    .collect()
            })
            .collect();
        Self { responses }
    }
}

/// [`solve_active_set`] from the classes `class`.
fn solve_from(
    bodies: &mut [IslandBody],
    contacts: &mut [Contact],
    rows: &[Row],
    w: &Couplings,
    tolerance: f64,
    mut class: Vec<Class>,
) -> Outcome {
    let n = contacts.len();
    let responses = &w.responses;
    let u_now: Vec<DVec3> = contacts
        .iter()
        .zip(rows)
        .map(|(c, r)| contact_velocity(bodies, c, r))
        .collect();
    let p_max = contacts.iter().map(|c| c.impulse.z).fold(0.0_f64, f64::max);
    // With nothing pressing yet there is no scale to judge a solution's size by.
    let pressing = p_max > 0.0;
    let p_max = p_max.max(f64::MIN_POSITIVE);
    // The active sets tried so far: one seen again is a cycle, which more rounds only repeat.
    let mut tried: Vec<Vec<Class>> = Vec::new();
    for _ in 0..MAX_ROUNDS {
        if tried.contains(&class) {
            return Outcome::Failed;
        }
        tried.push(class.clone());
        let mut offset = vec![usize::MAX; n];
        let mut m = 0;
        for k in 0..n {
            if class[k].unknowns() > 0 {
                offset[k] = m;
                m += class[k].unknowns();
            }
        }
        if m == 0 {
            return Outcome::Failed;
        }
        // What the classes force before any unknown: a contact that does not press drops its
        // impulse, a sliding one puts its friction on the cone's rim in its direction. The
        // linear system starts from the velocities after those changes (else the velocities
        // it solves for are not the ones the impulses it returns produce).
        let mut u_base = u_now.clone();
        for j in 0..n {
            let p = contacts[j].impulse;
            let forced = match class[j] {
                Class::Off => -p,
                Class::Stick => DVec3::ZERO,
                Class::Slide(d) => {
                    let rim = contacts[j].friction * p.z;
                    DVec3::new(rim * d.x - p.x, rim * d.y - p.y, 0.0)
                }
            };
            if forced != DVec3::ZERO {
                for &(i, unit) in &responses[j] {
                    u_base[i] += along(&unit, forced);
                }
            }
        }
        // W on the active set, column by column (compressed sparse columns, rows ascending).
        let mut a = Columns::new();
        let mut rhs = Mat::<f64>::zeros(m, 1);
        // Every non-zero response (contact, column, velocity change), Off contacts included:
        // their velocities after the solve say whether they must press.
        let mut entries: Vec<(usize, usize, DVec3)> = Vec::new();
        // Columns: the response of every neighbouring contact to one unknown's impulse.
        for j in 0..n {
            let (dirs, count) = match class[j] {
                Class::Off => continue,
                Class::Stick => ([DVec3::X, DVec3::Y, DVec3::Z], 3),
                Class::Slide(d) => {
                    let mu = contacts[j].friction;
                    (
                        [
                            DVec3::new(mu * d.x, mu * d.y, 1.0),
                            DVec3::ZERO,
                            DVec3::ZERO,
                        ],
                        1,
                    )
                }
            };
            for (q, dir) in dirs[..count].iter().enumerate() {
                let col = offset[j] + q;
                // `near` is ascending, and so are the offsets: the rows come in order.
                for &(i, unit) in &responses[j] {
                    let du = along(&unit, *dir);
                    entries.push((i, col, du));
                    match class[i] {
                        Class::Stick => {
                            for r in 0..3 {
                                a.push(offset[i] + r, du[r]);
                            }
                        }
                        Class::Slide(_) => a.push(offset[i], du.z),
                        Class::Off => {}
                    }
                }
                a.end_column();
            }
        }
        for k in 0..n {
            let target = contacts[k].target_normal_velocity;
            match class[k] {
                Class::Off => {}
                Class::Stick => {
                    rhs[(offset[k], 0)] = -u_base[k].x;
                    rhs[(offset[k] + 1, 0)] = -u_base[k].y;
                    rhs[(offset[k] + 2, 0)] = target - u_base[k].z;
                }
                Class::Slide(_) => rhs[(offset[k], 0)] = target - u_base[k].z,
            }
        }
        // Tikhonov on the *total* impulse, not on its change: min ‖W·ΔP − b‖ + λ‖P + ΔP‖ gives
        // (W + λ)·ΔP = b − λ·P. Along W's null space (the internal stresses of redundant
        // corners: pairs pushing or rubbing against each other to no effect) this sets
        // ΔP = −P exactly, whatever λ: the warm start's stresses are removed instead of
        // carried (they put resting corners on their friction cones, and the active set then
        // flipped between sticking and sliding every round without converging).
        let Some(lambda) = a.regularise(REGULARISATION) else {
            return Outcome::Failed;
        };
        for k in 0..n {
            let p = contacts[k].impulse;
            match class[k] {
                Class::Off => {}
                Class::Stick => {
                    for r in 0..3 {
                        rhs[(offset[k] + r, 0)] -= lambda * p[r];
                    }
                }
                Class::Slide(_) => rhs[(offset[k], 0)] -= lambda * p.z,
            }
        }
        let Some(x) = solve_linear(m, a, rhs) else {
            return Outcome::Failed;
        };
        if !(0..m).all(|i| x[(i, 0)].is_finite()) {
            return Outcome::Failed;
        }
        // The new impulses, and the laws.
        let new: Vec<DVec3> = (0..n)
            .map(|k| {
                let p = contacts[k].impulse;
                match class[k] {
                    Class::Off => DVec3::new(0.0, 0.0, 0.0),
                    Class::Stick => {
                        p + DVec3::new(
                            x[(offset[k], 0)],
                            x[(offset[k] + 1, 0)],
                            x[(offset[k] + 2, 0)],
                        )
                    }
                    Class::Slide(d) => {
                        let p_n = p.z + x[(offset[k], 0)];
                        let mu = contacts[k].friction;
                        DVec3::new(mu * p_n * d.x, mu * p_n * d.y, p_n)
                    }
                }
            })
            .collect();
        // A system whose solution dwarfs every impulse the iterate had is near-singular or
        // inconsistent (a loop of sticking contacts asked for speeds no rigid motion meets),
        // and its classes from here on are noise: give up and leave it to the sweeps.
        let largest = new.iter().map(|p| p.length()).fold(0.0_f64, f64::max);
        if pressing && largest > DIVERGED * p_max {
            return if tried.len() == 1 {
                Outcome::DivergedAtOnce
            } else {
                Outcome::Failed
            };
        }
        let mut u_after = u_base;
        for &(i, col, du) in &entries {
            u_after[i] += du * x[(col, 0)];
        }
        let mut changed = false;
        for k in 0..n {
            let c = &contacts[k];
            let u_t = DVec2::new(u_after[k].x, u_after[k].y);
            match class[k] {
                Class::Off if u_after[k].z < c.target_normal_velocity - tolerance => {
                    class[k] = Class::Stick;
                    changed = true;
                }
                // Sliding friction must oppose the slip it finds; slip that turned means the
                // contact sticks. Slip that stopped (within the tolerance) is a contact
                // sticking on its cone's rim, which the laws allow: flipping it to Stick
                // would put its friction just outside the cone, and the two classes would
                // alternate every round.
                Class::Slide(d) if u_t.dot(d) > tolerance => {
                    class[k] = Class::Stick;
                    changed = true;
                }
                // Sliding on: friction must point against the slip the solve finds, not
                // where the last guess put it.
                Class::Slide(d)
                    if u_t.length() > tolerance
                        && (-u_t / u_t.length()).dot(d) < SLIDE_DIRECTION_COS =>
                {
                    class[k] = Class::Slide(-u_t / u_t.length());
                    changed = true;
                }
                _ => {}
            }
        }
        for k in 0..n {
            let p = new[k];
            let cone = contacts[k].friction * p.z;
            match class[k] {
                Class::Stick | Class::Slide(_) if p.z < -LAW_SLACK * p_max => {
                    class[k] = Class::Off;
                    changed = true;
                }
                Class::Stick => {
                    let p_t = DVec2::new(p.x, p.y);
                    if p_t.length() > cone * (1.0 + LAW_SLACK) + LAW_SLACK * p_max {
                        class[k] = Class::Slide(p_t / p_t.length());
                        changed = true;
                    }
                }
                _ => {}
            }
        }
        if changed {
            continue;
        }
        // Accept: apply the change of every contact's impulse.
        for k in 0..n {
            let dp = new[k] - contacts[k].impulse;
            apply(bodies, &contacts[k], &rows[k], dp);
            contacts[k].impulse = new[k];
        }
        return Outcome::Accepted;
    }
    Outcome::Failed
}

/// A square matrix in compressed sparse columns, built column by column with ascending rows.
#[derive(Clone)]
struct Columns {
    /// Start of each column in `rows` and `values`, and the end of the last.
    starts: Vec<usize>,
    rows: Vec<usize>,
    values: Vec<f64>,
}

impl Columns {
    /// No columns yet.
    fn new() -> Self {
        Self {
            starts: vec![0],
            rows: Vec::new(),
            values: Vec::new(),
        }
    }

    /// Appends an entry to the current column (rows ascending).
    fn push(&mut self, row: usize, value: f64) {
        self.rows.push(row);
        self.values.push(value);
    }

    /// Ends the current column.
    fn end_column(&mut self) {
        self.starts.push(self.rows.len());
    }

    /// Columns so far.
    fn len(&self) -> usize {
        self.starts.len() - 1
    }

    /// The entry of column `c` and row `r`, or `None` where there is none.
    fn position(&self, r: usize, c: usize) -> Option<usize> {
        let range = self.starts[c]..self.starts[c + 1];
        self.rows[range.clone()]
            .binary_search(&r)
            .ok()
            .map(|k| range.start + k)
    }

    /// Whether this is a valid m × m pattern: m columns, rows below m and strictly ascending
    /// within each column (what faer's constructor requires; checked here so that a defect
    /// of the assembly is a failed solve, not a panic).
    fn is_valid(&self, m: usize) -> bool {
        self.len() == m
            && self.starts.windows(2).all(|w| {
                w[0] <= w[1]
                    && self.rows[w[0]..w[1]].windows(2).all(|r| r[0] < r[1])
                    && self.rows[w[0]..w[1]].iter().all(|&r| r < m)
            })
    }

    /// Adds λ = `relative` × the largest |diagonal entry| to every diagonal entry and returns
    /// λ; `None` when a diagonal entry is missing (a contact always responds to its own
    /// impulse, so that is a defect of the assembly).
    fn regularise(&mut self, relative: f64) -> Option<f64> {
        let diagonal: Vec<usize> = (0..self.len())
            .map(|i| self.position(i, i))
            .collect::<Option<_>>()?;
        let largest = diagonal
            .iter()
            .map(|&k| self.values[k].abs())
            .fold(0.0_f64, f64::max);
        let lambda = relative * largest;
        for k in diagonal {
            self.values[k] += lambda;
        }
        Some(lambda)
    }
}

/// A sparse pattern (column starts, row indices) and its symbolic LU.
type AnalysedPattern = (Vec<usize>, Vec<usize>, SymbolicLu<usize>);

thread_local! {
    /// The last sparse pattern factorised on this thread and its symbolic LU (fill-reducing
    /// ordering, elimination tree, supernodes): an island's active set usually repeats from
    /// one step to the next, and the symbolic analysis costs as much as the numeric
    /// factorisation. The analysis depends on the pattern alone, so reusing it changes no
    /// result.
    static LAST_SYMBOLIC: RefCell<Option<AnalysedPattern>> =
        const { RefCell::new(None) };
}

/// The symbolic LU of `sparse`'s pattern (supernodal, faer's column ordering), reused when
/// the pattern is the last one this thread analysed.
fn symbolic_lu(sparse: &SparseColMat<usize, f64>) -> Option<SymbolicLu<usize>> {
    let pattern = sparse.symbolic();
    let (starts, rows) = (pattern.col_ptr(), pattern.row_idx());
    LAST_SYMBOLIC.with(|last| {
        let mut last = last.borrow_mut();
        if let Some((s, r, symbolic)) = last.as_ref() {
            if s == starts && r == rows {
                return Some(symbolic.clone());
            }
        }
        let params = LuSymbolicParams {
            supernodal_flop_ratio_threshold: SupernodalThreshold::FORCE_SUPERNODAL,
            ..Default::default()
        };
        let symbolic = factorize_symbolic_lu(pattern, params).ok()?;
        *last = Some((starts.to_vec(), rows.to_vec(), symbolic.clone()));
        Some(symbolic)
    })
}

/// The response to the impulse `p` (contact frame) from the responses to the frame's unit
/// impulses: W is linear.
fn along(unit: &[DVec3; 3], p: DVec3) -> DVec3 {
    unit[0] * p.x + unit[1] * p.y + unit[2] * p.z
}

/// Solves A·x = rhs by a dense LU with partial pivoting, sequentially: faer's convenience
/// solver takes the global parallelism, and for the small systems of an island's direct solve
/// its thread hand-offs cost more than the factorisation (measured: 40 % of the dominos' run
/// in the kernel's scheduler).
pub(super) fn dense_solve(mut lu: Mat<f64>, mut rhs: Mat<f64>) -> Mat<f64> {
    let m = lu.nrows();
    let par = Par::Seq;
    let (mut forward, mut inverse) = (vec![0usize; m], vec![0usize; m]);
    let mut scratch = MemBuffer::new(
        lu_in_place_scratch::<usize, f64>(m, m, par, Default::default())
            .or(solve_in_place_scratch::<usize, f64>(m, 1, par)),
    );
    let (_, perm) = lu_in_place(
        lu.as_mut(),
        &mut forward,
        &mut inverse,
        par,
        MemStack::new(&mut scratch),
        Default::default(),
    );
    // The triangular solves read only their own triangle of the packed factors.
    solve_in_place_with_conj(
        lu.as_ref(),
        lu.as_ref(),
        perm,
        Conj::No,
        rhs.as_mut(),
        par,
        MemStack::new(&mut scratch),
    );
    rhs
}

/// Solves A·x = rhs for the m × m matrix `a`: dense LU up to [`DENSE_UP_TO`] unknowns,
/// sparse supernodal LU beyond, sequentially (the result must not depend on the thread
/// count). `None` when the sparse factorisation fails (a structurally singular system).
fn solve_linear(m: usize, a: Columns, mut rhs: Mat<f64>) -> Option<Mat<f64>> {
    if !a.is_valid(m) {
        return None;
    }
    if m <= DENSE_UP_TO {
        let mut dense = Mat::<f64>::zeros(m, m);
        for c in 0..m {
            for k in a.starts[c]..a.starts[c + 1] {
                dense[(a.rows[k], c)] = a.values[k];
            }
        }
        return Some(dense_solve(dense, rhs));
    }
    let pattern = SymbolicSparseColMat::<usize>::new_checked(m, m, a.starts, None, a.rows);
    let sparse = SparseColMat::<usize, f64>::new(pattern, a.values);
    let symbolic = symbolic_lu(&sparse)?;
    let mut numeric = NumericLu::new();
    let par = Par::Seq;
    let mut scratch = MemBuffer::try_new(
        symbolic
            .factorize_numeric_lu_scratch::<f64>(par, Default::default())
            .or(symbolic.solve_in_place_scratch::<f64>(1, par)),
    )
    .ok()?;
    let lu = symbolic
        .factorize_numeric_lu(
            &mut numeric,
            sparse.as_ref(),
            par,
            MemStack::new(&mut scratch),
            Default::default(),
        )
        .ok()?;
    lu.solve_in_place_with_conj(Conj::No, rhs.as_mut(), par, MemStack::new(&mut scratch));
    Some(rhs)
}

/// The change of contact `i`'s velocity (its frame) when world impulse `p` acts at contact
/// `j` (+p on its body 1, −p on its body 2).
fn response(
    bodies: &[IslandBody],
    contacts: &[Contact],
    rows: &[Row],
    i: usize,
    j: usize,
    p: DVec3,
) -> DVec3 {
    let (ci, cj) = (&contacts[i], &contacts[j]);
    let mut du = DVec3::ZERO;
    // Each body of contact j that is also a body of contact i.
    let bodies_j = [
        (Some(cj.body1), 1.0, rows[j].r1),
        (cj.body2, -1.0, rows[j].r2),
    ];
    let bodies_i = [
        (Some(ci.body1), 1.0, rows[i].r1),
        (ci.body2, -1.0, rows[i].r2),
    ];
    for &(bj, sj, rj) in &bodies_j {
        let Some(bj) = bj else { continue };
        let (dv, dw) = bodies[bj].body.velocity_change(rj, p * sj);
        for &(bi, si, ri) in &bodies_i {
            if bi == Some(bj) {
                du += si * (dv + dw.cross(ri));
            }
        }
    }
    rows[i].frame.to_contact(du)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A block-tridiagonal system like a stack's W (12 × 12 blocks), beyond the dense size:
    /// the sparse LU's solution satisfies A·x = b to rounding, checked by multiplying the
    /// entries out; the dense LU, given the same system, agrees.
    #[test]
    fn sparse_solve_of_a_block_tridiagonal_system_meets_its_equations() {
        let (block, blocks) = (12, 20);
        let m = block * blocks;
        assert!(m > DENSE_UP_TO);
        // A deterministic pseudo-random sequence (xorshift).
        let mut seed = 0x2545_f491_4f6c_dd1d_u64;
        let mut next = move || {
            seed ^= seed << 13;
            seed ^= seed >> 7;
            seed ^= seed << 17;
            (seed >> 11) as f64 / (1u64 << 53) as f64 - 0.5
        };
        let mut a = Columns::new();
        for c in 0..m {
            let k = c / block;
            let first = k.saturating_sub(1) * block;
            let last = ((k + 2) * block).min(m);
            for r in first..last {
                // Diagonally dominant, so the system is well conditioned.
                a.push(r, if r == c { 20.0 } else { next() });
            }
            a.end_column();
        }
        assert!(a.is_valid(m));
        let mut rhs = Mat::<f64>::zeros(m, 1);
        for i in 0..m {
            rhs[(i, 0)] = next();
        }
        let x = solve_linear(m, a.clone(), rhs.clone()).expect("regular system");
        let mut residual = vec![0.0; m];
        for c in 0..m {
            for k in a.starts[c]..a.starts[c + 1] {
                residual[a.rows[k]] += a.values[k] * x[(c, 0)];
            }
        }
        let worst = (0..m)
            .map(|i| (residual[i] - rhs[(i, 0)]).abs())
            .fold(0.0_f64, f64::max);
        assert!(worst < 1e-12, "largest residual {worst:e}");
    }

    /// A malformed pattern (rows out of order) is a failed solve, not a panic.
    #[test]
    fn a_malformed_pattern_is_refused() {
        let m = DENSE_UP_TO + 1;
        let mut a = Columns::new();
        for c in 0..m {
            a.push(c, 1.0);
            if c == 5 {
                a.push(0, 1.0);
            }
            a.end_column();
        }
        assert!(!a.is_valid(m));
        assert!(solve_linear(m, a, Mat::<f64>::zeros(m, 1)).is_none());
    }
}
