//! Reading STL meshes (binary and ASCII) as polygon meshes, for URDF `<mesh>` collision
//! geometry.
//!
//! STL is a triangle soup: each triangle carries its own three corners. Corners with bit-equal
//! coordinates are merged into one vertex (exporters write a shared corner with the same
//! numbers), which gives the closed, consistently oriented mesh a convex polyhedron is checked
//! from; the facet normals are ignored (the corner order gives the orientation). A file whose
//! length is exactly `84 + 50·n` for the triangle count `n` in its header is binary; otherwise
//! one that starts with `solid` is ASCII. Parsed here rather than by a crate because the
//! format is this small and an error must name the file and what is wrong with it.

use std::collections::HashMap;
use std::path::Path;

use glam::DVec3;
use impulse_geom::PolyMesh;

/// Reads an STL file.
///
/// # Errors
/// A sentence naming the file: unreadable, neither binary nor ASCII STL, a malformed number
/// or vertex count, no triangles, or a mesh [`PolyMesh::new`] refuses.
pub(super) fn read(path: &Path) -> Result<PolyMesh, String> {
    let bytes = std::fs::read(path).map_err(|e| format!("{}: {e}", path.display()))?;
    let corners = parse(&bytes).map_err(|e| format!("{}: {e}", path.display()))?;
    weld(&corners).map_err(|e| format!("{}: {e}", path.display()))
}

/// The triangles' corners, three per triangle.
fn parse(bytes: &[u8]) -> Result<Vec<DVec3>, String> {
    if bytes.len() >= 84 {
        let n = u32::from_le_bytes([bytes[80], bytes[81], bytes[82], bytes[83]]) as usize;
        if n.checked_mul(50).and_then(|b| b.checked_add(84)) == Some(bytes.len()) {
            return Ok(binary(&bytes[84..], n));
        }
    }
    let text = std::str::from_utf8(bytes)
        .map_err(|_| "not STL: neither binary (its length does not match the triangle count in its header) nor ASCII text".to_string())?;
    if !text.trim_start().starts_with("solid") {
        return Err(
            "not STL: neither binary (its length does not match the triangle count in its \
             header) nor ASCII (it does not start with `solid`)"
                .into(),
        );
    }
    ascii(text)
}

fn binary(body: &[u8], n: usize) -> Vec<DVec3> {
    let f = |b: &[u8], k: usize| {
        f64::from(f32::from_le_bytes([
            b[4 * k],
            b[4 * k + 1],
            b[4 * k + 2],
            b[4 * k + 3],
        ]))
    };
    let mut out = Vec::with_capacity(3 * n);
    for t in body.chunks_exact(50) {
        // 12 bytes of normal, then three corners of 12 bytes, then 2 attribute bytes.
        for c in 0..3 {
            let at = 3 + 3 * c;
            out.push(DVec3::new(f(t, at), f(t, at + 1), f(t, at + 2)));
        }
    }
    out
}

fn ascii(text: &str) -> Result<Vec<DVec3>, String> {
    let mut out = Vec::new();
    for (k, line) in text.lines().enumerate() {
        let mut words = line.split_whitespace();
        if words.next() != Some("vertex") {
            continue;
        }
        let mut xyz = [0.0; 3];
        for x in &mut xyz {
            let w = words
                .next()
                .ok_or_else(|| format!("line {}: a vertex needs three numbers", k + 1))?;
            *x = w
                .parse()
                .map_err(|_| format!("line {}: `{w}` is not a number", k + 1))?;
        }
        out.push(DVec3::from_array(xyz));
    }
    if out.len() % 3 != 0 {
        return Err(format!(
            "{} vertices do not make whole triangles",
            out.len()
        ));
    }
    Ok(out)
}

/// Merges bit-equal corners into shared vertices.
fn weld(corners: &[DVec3]) -> Result<PolyMesh, String> {
    if corners.is_empty() {
        return Err("no triangles".into());
    }
    let mut index: HashMap<[u64; 3], u32> = HashMap::new();
    let mut vertices = Vec::new();
    let mut faces = Vec::with_capacity(corners.len() / 3);
    for tri in corners.chunks_exact(3) {
        let mut face = [0u32; 3];
        for (slot, p) in face.iter_mut().zip(tri) {
            let key = [p.x.to_bits(), p.y.to_bits(), p.z.to_bits()];
            *slot = *index.entry(key).or_insert_with(|| {
                vertices.push(*p);
                (vertices.len() - 1) as u32
            });
        }
        faces.push(face);
    }
    PolyMesh::new(vertices, faces).map_err(|e| e.to_string())
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A unit cube's 12 triangles, counter-clockwise seen from outside.
    fn cube_triangles(h: f64) -> Vec<[DVec3; 3]> {
        let c = |i: usize| {
            DVec3::new(
                if i & 1 == 1 { h } else { -h },
                if i & 2 == 2 { h } else { -h },
                if i & 4 == 4 { h } else { -h },
            )
        };
        // Quads as corner indices (counter-clockwise from outside), split into two triangles.
        let quads = [
            [0, 2, 3, 1],
            [4, 5, 7, 6],
            [0, 1, 5, 4],
            [2, 6, 7, 3],
            [0, 4, 6, 2],
            [1, 3, 7, 5],
        ];
        quads
            .iter()
            .flat_map(|q| [[c(q[0]), c(q[1]), c(q[2])], [c(q[0]), c(q[2]), c(q[3])]])
            .collect()
    }

    fn binary_file(tris: &[[DVec3; 3]]) -> Vec<u8> {
        // A header starting like ASCII STL (some exporters do) must not confuse the reader.
        let mut b = b"solid binary".to_vec();
        b.resize(80, b' ');
        b.extend_from_slice(&(tris.len() as u32).to_le_bytes());
        for t in tris {
            b.extend_from_slice(&[0u8; 12]);
            for p in t {
                for x in p.to_array() {
                    b.extend_from_slice(&(x as f32).to_le_bytes());
                }
            }
            b.extend_from_slice(&[0u8; 2]);
        }
        b
    }

    fn ascii_file(tris: &[[DVec3; 3]]) -> String {
        let mut s = String::from("solid cube\n");
        for t in tris {
            s.push_str("  facet normal 0 0 0\n    outer loop\n");
            for p in t {
                s.push_str(&format!("      vertex {} {} {}\n", p.x, p.y, p.z));
            }
            s.push_str("    endloop\n  endfacet\n");
        }
        s.push_str("endsolid cube\n");
        s
    }

    /// Both encodings of a cube give its 8 corners and a closed mesh of volume (2h)³.
    #[test]
    fn binary_and_ascii_cubes_weld_to_eight_corners() {
        let tris = cube_triangles(0.25);
        for bytes in [binary_file(&tris), ascii_file(&tris).into_bytes()] {
            let mesh = weld(&parse(&bytes).unwrap()).unwrap();
            assert_eq!((mesh.vertices().len(), mesh.faces().len()), (8, 12));
            let poly = impulse_geom::ConvexPolyhedron::from_mesh(&mesh).unwrap();
            let mp = impulse_massprops::MassProperties::from_convex(&poly, 1.0).unwrap();
            assert!((mp.mass - 0.125).abs() < 1e-15, "volume {}", mp.mass);
        }
    }

    #[test]
    fn malformed_files_say_why() {
        assert!(parse(b"hello").unwrap_err().contains("not STL"));
        let cut = &binary_file(&cube_triangles(1.0))[..200];
        assert!(parse(cut).unwrap_err().contains("not STL"));
        let bad = "solid x\n vertex 1 2\n";
        assert!(parse(bad.as_bytes()).unwrap_err().contains("line 2"));
        let two = "solid x\n vertex 1 2 3\n vertex 1 2 4\nendsolid\n";
        assert!(
            parse(two.as_bytes())
                .unwrap_err()
                .contains("whole triangles")
        );
        assert!(weld(&[]).unwrap_err().contains("no triangles"));
    }
}
