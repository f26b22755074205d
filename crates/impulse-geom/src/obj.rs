//! Reading and writing polygon meshes as Wavefront OBJ.
//!
//! Only geometry is read: `v` (positions) and `f` (faces, with `i`, `i/t`, `i//n` or `i/t/n`
//! corners and negative, relative indices). Every other statement (`vt`, `vn`, `o`, `g`, `s`,
//! `usemtl`, `mtllib`, `l`, `p`, ...) carries no volume and is skipped. Lines may be continued
//! with a trailing backslash. Faces are kept as polygons, not triangulated: the mass-property
//! integration handles any polygon, and triangulating would only add error.
//!
//! We parse OBJ ourselves rather than use a crate because the subset is tiny and an error must
//! name the file and line, which the common OBJ crates do not report.

use std::fmt::Write as _;
use std::path::Path;

use glam::DVec3;

use crate::error::GeomError;
use crate::mesh::PolyMesh;

/// Most faces [`parse`] reads before it refuses a mesh, checked as the faces are read (so a
/// mesh far over it is refused in a moment, not after its hull is built). A convex part or a
/// collision shape needs far fewer: every pose study and collision query costs more with
/// each face, and a hull of 1.3 million faces took 29 s and 1.9 GB before its first drop.
/// [`parse_with_limit`] reads larger meshes. Default `200 000`.
pub const MAX_FACES: usize = 200_000;

/// Parses OBJ text into a [`PolyMesh`]. `source_name` (a file name, or `"<string>"`) is used in
/// error messages.
///
/// # Errors
/// [`GeomError::Obj`] with the line number for malformed statements, bad or out-of-range
/// indices, non-finite coordinates, or more than [`MAX_FACES`] faces; the [`PolyMesh::new`]
/// errors for faces that are too small or repeat a vertex (with the face number).
pub fn parse(text: &str, source_name: &str) -> Result<PolyMesh, GeomError> {
    parse_with_limit(text, source_name, MAX_FACES)
}

/// [`parse`] with another limit on the number of faces than [`MAX_FACES`].
///
/// # Errors
/// As [`parse`], with `max_faces` as the limit.
pub fn parse_with_limit(
    text: &str,
    source_name: &str,
    max_faces: usize,
) -> Result<PolyMesh, GeomError> {
    let err = |line: usize, message: String| GeomError::Obj {
        source_name: source_name.to_owned(),
        line,
        message,
    };
    let mut vertices: Vec<DVec3> = Vec::new();
    let mut faces: Vec<Vec<u32>> = Vec::new();
    // Logical lines: join backslash continuations, remembering the first physical line number.
    let mut pending = String::new();
    let mut pending_start = 0;
    for (n, raw) in text.lines().enumerate() {
        let line_no = n + 1;
        if pending.is_empty() {
            pending_start = line_no;
        }
        let content = raw.split('#').next().unwrap_or("");
        if let Some(stripped) = content.trim_end().strip_suffix('\\') {
            pending.push_str(stripped);
            pending.push(' ');
            continue;
        }
        pending.push_str(content);
        let logical = std::mem::take(&mut pending);
        let line = pending_start;
        let mut tokens = logical.split_whitespace();
        match tokens.next() {
            Some("v") => {
                let mut xyz = [0.0; 3];
                for (k, c) in xyz.iter_mut().enumerate() {
                    let t = tokens
                        .next()
                        .ok_or_else(|| err(line, format!("vertex needs 3 coordinates, got {k}")))?;
                    *c = t
                        .parse::<f64>()
                        .map_err(|_| err(line, format!("bad vertex coordinate {t:?}")))?;
                    if !c.is_finite() {
                        return Err(err(line, format!("non-finite vertex coordinate {t:?}")));
                    }
                }
                if let Some(w) = tokens.next() {
                    let w: f64 = w
                        .parse()
                        .map_err(|_| err(line, format!("bad vertex weight {w:?}")))?;
                    if w != 1.0 {
                        return Err(err(
                            line,
                            format!("vertex weight w = {w} is not supported (only w = 1)"),
                        ));
                    }
                }
                vertices.push(DVec3::from_array(xyz));
            }
            Some("f") => {
                let mut face = Vec::new();
                for t in tokens {
                    let idx = t.split('/').next().unwrap_or("");
                    let i: i64 = idx
                        .parse()
                        .map_err(|_| err(line, format!("bad face index {t:?}")))?;
                    // OBJ indices are 1-based; negative ones count back from the last vertex.
                    let resolved = match i {
                        i if i > 0 => i - 1,
                        i if i < 0 => vertices.len() as i64 + i,
                        _ => {
                            return Err(err(
                                line,
                                "face index 0 is invalid (OBJ is 1-based)".into(),
                            ));
                        }
                    };
                    if resolved < 0 || resolved >= vertices.len() as i64 {
                        return Err(err(
                            line,
                            format!(
                                "face index {i} refers to a vertex not defined before this line \
                                 ({} so far)",
                                vertices.len()
                            ),
                        ));
                    }
                    face.push(resolved as u32);
                }
                if face.len() < 3 {
                    return Err(err(
                        line,
                        format!("face has {} vertices, needs 3", face.len()),
                    ));
                }
                if faces.len() == max_faces {
                    return Err(err(
                        line,
                        format!(
                            "more than {max_faces} faces, the limit of a mesh read for a body \
                             (impulse_geom::obj::MAX_FACES): simplify the mesh (a convex part \
                             needs far fewer), or read it with obj::parse_with_limit"
                        ),
                    ));
                }
                faces.push(face);
            }
            _ => {}
        }
    }
    if faces.is_empty() {
        return Err(err(text.lines().count(), "no faces found".into()));
    }
    PolyMesh::new(vertices, faces)
}

/// Reads an OBJ file into a [`PolyMesh`].
///
/// # Errors
/// [`GeomError::Io`] if the file cannot be read; otherwise as [`parse`].
pub fn read(path: &Path) -> Result<PolyMesh, GeomError> {
    let text = std::fs::read_to_string(path).map_err(|source| GeomError::Io {
        path: path.to_owned(),
        source,
    })?;
    parse(&text, &path.display().to_string())
}

/// Formats a mesh as OBJ text. Coordinates are written with the shortest representation that
/// reads back to the identical `f64`, so [`parse`] of the result reproduces the mesh exactly.
pub fn to_string(mesh: &PolyMesh) -> String {
    let mut s = String::new();
    for v in mesh.vertices() {
        let _ = writeln!(s, "v {:?} {:?} {:?}", v.x, v.y, v.z);
    }
    for face in mesh.faces() {
        s.push('f');
        for &i in face {
            let _ = write!(s, " {}", i + 1);
        }
        s.push('\n');
    }
    s
}

/// Writes a mesh to an OBJ file (see [`to_string`]).
///
/// # Errors
/// [`GeomError::Io`] if the file cannot be written.
pub fn write(mesh: &PolyMesh, path: &Path) -> Result<(), GeomError> {
    std::fs::write(path, to_string(mesh)).map_err(|source| GeomError::Io {
        path: path.to_owned(),
        source,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    const TETRA: &str = "# a tetrahedron\nv 0 0 0\nv 1 0 0\nv 0 1 0\nv 0 0 1\n\
                         vn 0 0 1\nf 1 3 2\nf 1/1/1 2/2/1 4/3/1\nf 1//1 4//1 3//1\nf -3 -2 -1\n";

    /// A mesh of more faces than the limit is refused at the first face over it, naming the
    /// limit and the line; at the limit it reads. The default limit is [`MAX_FACES`]: a mesh
    /// of one face more than it is refused by [`parse`].
    #[test]
    fn a_mesh_over_the_face_limit_is_refused_naming_it() {
        let fan = |n: usize| {
            let mut text = String::from("v 0 0 0\n");
            for k in 0..=n {
                let a = k as f64;
                let _ = writeln!(text, "v {} {} 0", a.cos(), a.sin());
            }
            for k in 0..n {
                let _ = writeln!(text, "f 1 {} {}", k + 2, k + 3);
            }
            text
        };
        let mesh = parse_with_limit(&fan(10), "fan.obj", 10).unwrap();
        assert_eq!(mesh.face_count(), 10);
        let e = parse_with_limit(&fan(11), "fan.obj", 10)
            .unwrap_err()
            .to_string();
        // The 11th face is on line 1 + 12 + 11.
        assert!(
            e.contains("fan.obj:24") && e.contains("more than 10 faces"),
            "{e}"
        );
        let e = parse(&fan(MAX_FACES + 1), "big.obj")
            .unwrap_err()
            .to_string();
        assert!(e.contains(&format!("more than {MAX_FACES} faces")), "{e}");
    }

    #[test]
    fn parses_all_corner_forms_and_negative_indices() {
        let m = parse(TETRA, "t.obj").unwrap();
        assert_eq!(m.vertices().len(), 4);
        assert_eq!(m.face(0), &[0, 2, 1]);
        assert_eq!(m.face(1), &[0, 1, 3]);
        assert_eq!(m.face(2), &[0, 3, 2]);
        assert_eq!(m.face(3), &[1, 2, 3]);
        // The tetrahedron with legs 1 has volume 1/6: an independent check that the parsed
        // faces are the closed outward surface the text describes.
        assert!((m.check_closed().map(|_| m.signed_volume()).unwrap() - 1.0 / 6.0).abs() < 1e-15);
    }

    #[test]
    fn round_trip_is_exact() {
        let m = PolyMesh::new(
            vec![
                DVec3::new(0.1, 1.0 / 3.0, -2e-300),
                DVec3::new(1e300, 0.7, 3.0),
                DVec3::ONE,
            ],
            [[0u32, 1, 2]],
        )
        .unwrap();
        assert_eq!(parse(&to_string(&m), "x").unwrap(), m);
    }

    #[test]
    fn errors_name_the_line() {
        let e = parse("v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 5\n", "a.obj").unwrap_err();
        assert!(e.to_string().starts_with("a.obj:4:"), "{e}");
        let e = parse("v 0 0\n", "b.obj").unwrap_err();
        assert!(e.to_string().starts_with("b.obj:1:"), "{e}");
        let e = parse("v 0 nan 0\n", "c.obj").unwrap_err();
        assert!(e.to_string().contains("non-finite"), "{e}");
        let e = parse("v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 0\n", "d.obj").unwrap_err();
        assert!(e.to_string().contains("1-based"), "{e}");
        let e = parse("v 0 0 0\n", "e.obj").unwrap_err();
        assert!(e.to_string().contains("no faces"), "{e}");
        let e = parse("v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 x\n", "f.obj").unwrap_err();
        assert!(e.to_string().contains("bad face index"), "{e}");
    }

    #[test]
    fn continuation_lines_join() {
        let m = parse("v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 \\\n 2 3\n", "x").unwrap();
        assert_eq!(m.face(0), &[0, 1, 2]);
    }
}
