//! Broad-phase update rounds on the settling workload (thesis §2.4.2, Table 2.1: coherent
//! hashing ran 6.0–7.2× faster than standard hashing in four simulations).
//!
//! `round/coherent/N`: update every box of N, then take the new close pairs (what the simulator
//! does before each integration step). `round/standard/N`: set every box, then rebuild the
//! standard table from scratch. Boxes: sizes log-uniform over a ratio of 100; each round 99% of
//! them move by up to 2% of their size per axis and 1% by up to 4 sizes (see
//! `src/workload.rs`). The states cycle forwards and backwards through a precomputed sequence,
//! so consecutive rounds always differ by one workload step.
//!
//! Before timing, the deterministic work of 100 rounds is printed for both variants, with its
//! ratio. Run: `cargo bench -p impulse-broadphase`.

use criterion::{BenchmarkId, Criterion, criterion_group, criterion_main};
use impulse_broadphase::{CoherentHash, Levels, StandardHash, WorkCounters};
use impulse_geom::Aabb;
use std::hint::black_box;

#[path = "../src/workload.rs"]
#[allow(dead_code)] // shared with the unit tests, which use more of it
mod workload;

use workload::Settling;

/// Body counts benchmarked.
const SIZES: [usize; 2] = [1_000, 10_000];
/// Distinct precomputed states per body count (the cycle is twice as long).
const STATES: usize = 32;
/// Rounds summed for the printed work ratio.
const WORK_ROUNDS: usize = 100;
/// Workload seed.
const SEED: u64 = 2024;

fn levels() -> Levels {
    let lo = workload::SIZE_MIN;
    Levels::from_size_range(lo, workload::size_max(), 0.5, 1.0).expect("valid size range")
}

/// Index into the state list for round `i`: 0, 1, …, STATES−1, STATES−2, …, 1, 0, 1, …
fn ping_pong(i: usize) -> usize {
    let period = 2 * (STATES - 1);
    let j = i % period;
    if j < STATES { j } else { period - j }
}

fn states(n: usize) -> Vec<Vec<(u32, Aabb)>> {
    let mut w = Settling::new(n, SEED);
    (0..STATES)
        .map(|_| {
            let s = w.boxes().to_vec();
            w.step();
            s
        })
        .collect()
}

fn coherent_table(first: &[(u32, Aabb)]) -> CoherentHash {
    let mut h = CoherentHash::new(levels());
    for &(id, b) in first {
        h.insert(id, b).expect("valid box");
    }
    h.take_new_close_pairs();
    h
}

fn standard_table(first: &[(u32, Aabb)]) -> StandardHash {
    let mut h = StandardHash::new(levels());
    for &(id, b) in first {
        h.insert(id, b).expect("valid box");
    }
    h.rebuild();
    h
}

fn coherent_round(h: &mut CoherentHash, boxes: &[(u32, Aabb)]) -> usize {
    for &(id, b) in boxes {
        h.update(id, b).expect("valid box");
    }
    h.take_new_close_pairs().len()
}

fn standard_round(h: &mut StandardHash, boxes: &[(u32, Aabb)]) -> usize {
    for &(id, b) in boxes {
        h.update(id, b).expect("valid box");
    }
    h.rebuild();
    h.close_pair_count()
}

/// Prints the work of WORK_ROUNDS settling rounds, coherent vs standard.
fn report_work(n: usize) {
    let mut w = Settling::new(n, SEED);
    let mut c = coherent_table(w.boxes());
    let mut s = standard_table(w.boxes());
    c.reset_work();
    s.reset_work();
    for _ in 0..WORK_ROUNDS {
        w.step();
        coherent_round(&mut c, w.boxes());
        standard_round(&mut s, w.boxes());
    }
    let (cw, sw) = (c.work(), s.work());
    let table = |w: &WorkCounters| w.total() - w.cell_ranges;
    println!(
        "work, {n} bodies, {WORK_ROUNDS} rounds: coherent {cw:?}\n  standard {sw:?}\n  \
         ratio standard/coherent: total {:.1}, bucket work (without range computations) {:.1}; \
         close pairs now {}",
        sw.total() as f64 / cw.total() as f64,
        table(&sw) as f64 / table(&cw) as f64,
        c.close_pair_count(),
    );
}

fn rounds(c: &mut Criterion) {
    for n in SIZES {
        report_work(n);
    }
    let mut group = c.benchmark_group("round");
    for n in SIZES {
        let states = states(n);
        let mut h = coherent_table(&states[0]);
        let mut i = 0;
        group.bench_with_input(BenchmarkId::new("coherent", n), &states, |b, st| {
            b.iter(|| {
                i += 1;
                black_box(coherent_round(&mut h, &st[ping_pong(i)]))
            })
        });
        let mut h = standard_table(&states[0]);
        let mut i = 0;
        group.bench_with_input(BenchmarkId::new("standard", n), &states, |b, st| {
            b.iter(|| {
                i += 1;
                black_box(standard_round(&mut h, &st[ping_pong(i)]))
            })
        });
    }
    group.finish();
}

criterion_group!(benches, rounds);
criterion_main!(benches);
