//! Mass properties of geodesic spheres, levels 1–7 (thesis Table 6.2 and §6.4: 350 ms for
//! 20,480 faces on a 200 MHz R4400; about 4× per level, since each level has 4× the faces).
//!
//! `integrals/N` times the ten volume integrals alone, as the thesis did; `validated/N` times
//! `MassProperties::from_mesh`, which first checks that the mesh is closed and outward. The
//! throughput column is faces per second. Run: `cargo bench -p impulse-massprops`.

use criterion::{BenchmarkId, Criterion, Throughput, criterion_group, criterion_main};
use impulse_geom::primitives::geodesic_sphere_mesh;
use impulse_massprops::{MassProperties, VolumeIntegrals};
use std::hint::black_box;

fn geodesic(c: &mut Criterion) {
    let mut group = c.benchmark_group("geodesic");
    for level in 1..=7u32 {
        let Ok(mesh) = geodesic_sphere_mesh(level, 1.0) else {
            continue;
        };
        group.throughput(Throughput::Elements(mesh.face_count() as u64));
        group.bench_with_input(BenchmarkId::new("integrals", level), &mesh, |b, m| {
            b.iter(|| VolumeIntegrals::integrate(black_box(m), glam::DVec3::ZERO))
        });
        group.bench_with_input(BenchmarkId::new("validated", level), &mesh, |b, m| {
            b.iter(|| MassProperties::from_mesh(black_box(m), 1.0))
        });
    }
    group.finish();
}

criterion_group!(benches, geodesic);
criterion_main!(benches);
