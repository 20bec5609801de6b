//! Mesh writers: round-trips, streaming (interleaved) order, atomicity and clean-up.

use std::path::{Path, PathBuf};
use sweeptin::Error;
use sweeptin::input::read_ply;
use sweeptin::output::{MeshFormat, MeshMeta, create_mesh_sink};

/// A grid mesh with awkward coordinates, and the order a streaming triangulation would emit it:
/// a row of vertices, then the triangles between it and the previous row.
struct Grid {
    vertices: Vec<[f64; 3]>,
    triangles: Vec<[u64; 3]>,
    /// `Ok(v)` = push vertex v, `Err(t)` = push triangle t.
    order: Vec<Result<usize, usize>>,
}

fn grid(nx: usize, ny: usize) -> Grid {
    let mut g = Grid {
        vertices: Vec::new(),
        triangles: Vec::new(),
        order: Vec::new(),
    };
    for j in 0..ny {
        for i in 0..nx {
            let v = g.vertices.len();
            // UTM-sized, 1 cm grid with a 5 mm offset, like the ARSO tile; plus a few values whose
            // shortest decimal is long.
            let x = 511_000.005 + i as f64 * 0.37 + (v % 3) as f64 / 3.0;
            let y = 122_000.015 + j as f64 * 0.41;
            let z = 247.125 + (v as f64).sqrt() * 1e-3 - 1e-9 * v as f64;
            g.vertices.push([x, y, z]);
            g.order.push(Ok(v));
        }
        if j > 0 {
            for i in 0..nx - 1 {
                let a = ((j - 1) * nx + i) as u64;
                let (b, c, d) = (a + 1, a + nx as u64, a + nx as u64 + 1);
                for t in [[a, b, d], [a, d, c]] {
                    g.order.push(Err(g.triangles.len()));
                    g.triangles.push(t);
                }
            }
        }
    }
    g
}

fn meta() -> MeshMeta {
    MeshMeta {
        crs: Some("EPSG:3794".into()),
        comments: vec!["test mesh".into(), "second\nline".into()],
    }
}

fn write(path: &Path, format: Option<MeshFormat>, g: &Grid) -> sweeptin::sink::MeshSummary {
    let mut sink = create_mesh_sink(path, format, &meta()).unwrap();
    for step in &g.order {
        match *step {
            Ok(v) => sink.vertex(g.vertices[v]).unwrap(),
            Err(t) => sink.triangle(g.triangles[t]).unwrap(),
        }
    }
    sink.finish().unwrap()
}

fn dir_names(dir: &Path) -> Vec<String> {
    let mut v: Vec<String> = std::fs::read_dir(dir)
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .collect();
    v.sort();
    v
}

fn bits(p: [f64; 3]) -> [u64; 3] {
    p.map(f64::to_bits)
}

#[test]
fn ply_round_trip_interleaved() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("grid.ply");
    let g = grid(37, 23);
    let s = write(&path, None, &g);
    assert_eq!(s.vertices, g.vertices.len() as u64);
    assert_eq!(s.triangles, g.triangles.len() as u64);
    assert_eq!(s.bytes, std::fs::metadata(&path).unwrap().len());
    assert_eq!(dir_names(dir.path()), ["grid.ply"]);

    let (v, t) = read_ply(&path).unwrap();
    assert_eq!(v.len(), g.vertices.len());
    for (a, b) in v.iter().zip(&g.vertices) {
        assert_eq!(bits(*a), bits(*b));
    }
    let want: Vec<[u32; 3]> = g.triangles.iter().map(|t| t.map(|i| i as u32)).collect();
    assert_eq!(t, want);

    let bytes = std::fs::read(&path).unwrap();
    let end = bytes
        .windows(11)
        .position(|w| w == b"end_header\n")
        .unwrap()
        + 11;
    let header = String::from_utf8(bytes[..end].to_vec()).unwrap();
    assert!(
        header.starts_with("ply\nformat binary_little_endian 1.0\n"),
        "{header}"
    );
    assert!(header.contains("comment crs EPSG:3794\n"), "{header}");
    assert!(header.contains("comment second line\n"), "{header}");
    assert!(header.contains(&format!("element vertex {}\n", g.vertices.len())));
    assert!(header.contains("property list uchar uint vertex_indices\n"));
    assert_eq!(
        bytes.len(),
        end + 24 * g.vertices.len() + 13 * g.triangles.len()
    );
}

#[test]
fn ply_empty_and_points_only() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("empty.ply");
    let mut sink = create_mesh_sink(&path, None, &MeshMeta::default()).unwrap();
    let s = sink.finish().unwrap();
    assert_eq!((s.vertices, s.triangles), (0, 0));
    assert_eq!(read_ply(&path).unwrap(), (vec![], vec![]));

    let mut sink = create_mesh_sink(&path, None, &MeshMeta::default()).unwrap();
    sink.vertex([1.0, 2.0, 3.0]).unwrap();
    sink.finish().unwrap();
    assert_eq!(read_ply(&path).unwrap(), (vec![[1.0, 2.0, 3.0]], vec![]));
}

/// Minimal OBJ parser for the test: `v` and `f` lines, `#` comments.
fn parse_obj(text: &str) -> (Vec<[f64; 3]>, Vec<[u64; 3]>, Vec<String>) {
    let (mut v, mut f, mut c) = (Vec::new(), Vec::new(), Vec::new());
    for line in text.lines() {
        let mut w = line.split(' ');
        match w.next() {
            Some("v") => {
                let p: Vec<f64> = w.map(|s| s.parse().unwrap()).collect();
                v.push([p[0], p[1], p[2]]);
            }
            Some("f") => {
                let t: Vec<u64> = w.map(|s| s.parse().unwrap()).collect();
                assert!(t.iter().all(|&i| i >= 1 && i <= v.len() as u64), "{line}");
                f.push([t[0] - 1, t[1] - 1, t[2] - 1]);
            }
            Some("#") => c.push(line[2..].to_string()),
            _ => panic!("unexpected OBJ line {line:?}"),
        }
    }
    (v, f, c)
}

#[test]
fn obj_round_trip_interleaved() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("grid.obj");
    let g = grid(19, 11);
    let s = write(&path, None, &g);
    assert_eq!(s.bytes, std::fs::metadata(&path).unwrap().len());
    let text = std::fs::read_to_string(&path).unwrap();
    let (v, f, c) = parse_obj(&text);
    assert_eq!(v.len(), g.vertices.len());
    for (a, b) in v.iter().zip(&g.vertices) {
        assert_eq!(bits(*a), bits(*b), "OBJ text must round-trip exactly");
    }
    assert_eq!(f, g.triangles);
    assert!(c.contains(&"crs EPSG:3794".to_string()), "{c:?}");
    // Streaming: the first face comes right after the second row of vertices.
    let first_f = text.lines().position(|l| l.starts_with("f ")).unwrap();
    let n_comments = c.len();
    assert_eq!(first_f, n_comments + 2 * 19);
    assert_eq!(dir_names(dir.path()), ["grid.obj"]);
}

/// Minimal LandXML parser for the test: `<P id="i">N E Z</P>` and `<F>a b c</F>`.
fn parse_landxml(text: &str) -> (Vec<[f64; 3]>, Vec<[u64; 3]>) {
    let (mut v, mut f) = (Vec::new(), Vec::new());
    for line in text.lines() {
        if let Some(rest) = line.strip_prefix("<P id=\"") {
            let (id, rest) = rest.split_once("\">").unwrap();
            assert_eq!(id.parse::<usize>().unwrap(), v.len() + 1);
            let nums: Vec<f64> = rest
                .strip_suffix("</P>")
                .unwrap()
                .split(' ')
                .map(|s| s.parse().unwrap())
                .collect();
            // northing easting elevation = y x z
            v.push([nums[1], nums[0], nums[2]]);
        } else if let Some(rest) = line.strip_prefix("<F>") {
            let t: Vec<u64> = rest
                .strip_suffix("</F>")
                .unwrap()
                .split(' ')
                .map(|s| s.parse().unwrap())
                .collect();
            f.push([t[0] - 1, t[1] - 1, t[2] - 1]);
        }
    }
    (v, f)
}

#[test]
fn landxml_round_trip_interleaved() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("surface.xml");
    let g = grid(23, 17);
    let s = write(&path, None, &g);
    assert_eq!(s.bytes, std::fs::metadata(&path).unwrap().len());
    let text = std::fs::read_to_string(&path).unwrap();
    let (v, f) = parse_landxml(&text);
    assert_eq!(v.len(), g.vertices.len());
    for (a, b) in v.iter().zip(&g.vertices) {
        assert_eq!(bits(*a), bits(*b));
    }
    assert_eq!(f, g.triangles);
    // Structure: Pnts strictly before Faces, one Surface named after the file, CRS recorded.
    let pos = |s: &str| text.find(s).unwrap_or_else(|| panic!("no {s} in\n{text}"));
    assert!(pos("<Units>") < pos("<Surfaces>"));
    assert!(pos("</Pnts>") < pos("<Faces>"));
    assert!(text.contains("<Surface name=\"surface\">"));
    assert!(text.contains("<Definition surfType=\"TIN\">"));
    assert!(text.contains("epsgCode=\"3794\""));
    assert!(text.contains("<LandXML xmlns=\"http://www.landxml.org/schema/LandXML-1.2\""));
    assert!(text.trim_end().ends_with("</LandXML>"));
    assert_eq!(text.matches("<P ").count(), g.vertices.len());
    assert_eq!(dir_names(dir.path()), ["surface.xml"]);
}

#[test]
fn explicit_format_overrides_extension() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("mesh.txt");
    let g = grid(3, 3);
    write(&path, Some(MeshFormat::Obj), &g);
    let (v, f, _) = parse_obj(&std::fs::read_to_string(&path).unwrap());
    assert_eq!((v.len(), f.len()), (9, 8));
}

fn all_formats(dir: &Path) -> Vec<PathBuf> {
    ["a.ply", "a.obj", "a.xml"]
        .iter()
        .map(|n| dir.join(n))
        .collect()
}

#[test]
fn dropping_without_finish_leaves_nothing() {
    let dir = tempfile::tempdir().unwrap();
    for path in all_formats(dir.path()) {
        let mut sink = create_mesh_sink(&path, None, &meta()).unwrap();
        for p in grid(4, 4).vertices {
            sink.vertex(p).unwrap();
        }
        sink.triangle([0, 1, 5]).unwrap();
        drop(sink);
        assert_eq!(
            dir_names(dir.path()),
            Vec::<String>::new(),
            "{}",
            path.display()
        );
    }
}

#[test]
fn contract_errors_then_drop_leave_nothing() {
    let dir = tempfile::tempdir().unwrap();
    for path in all_formats(dir.path()) {
        let mut sink = create_mesh_sink(&path, None, &meta()).unwrap();
        sink.vertex([0.0, 0.0, 0.0]).unwrap();
        sink.vertex([1.0, 0.0, 0.0]).unwrap();
        let e = sink.triangle([0, 1, 2]).unwrap_err();
        assert!(matches!(e, Error::Output { .. }), "{e}");
        assert!(e.to_string().contains("vertex 2"), "{e}");
        let e = sink.vertex([f64::NAN, 0.0, 0.0]).unwrap_err();
        assert!(e.to_string().contains("non-finite"), "{e}");
        drop(sink);
        assert!(dir_names(dir.path()).is_empty(), "{}", path.display());
    }
}

#[test]
fn finish_twice_and_use_after_finish_are_errors() {
    let dir = tempfile::tempdir().unwrap();
    for path in all_formats(dir.path()) {
        let mut sink = create_mesh_sink(&path, None, &meta()).unwrap();
        for p in grid(2, 2).vertices {
            sink.vertex(p).unwrap();
        }
        sink.triangle([0, 1, 3]).unwrap();
        sink.finish().unwrap();
        assert!(sink.finish().is_err());
        assert!(sink.vertex([0.0; 3]).is_err());
        assert!(sink.triangle([0, 1, 2]).is_err());
        drop(sink);
        assert!(path.exists());
    }
    assert_eq!(dir_names(dir.path()), ["a.obj", "a.ply", "a.xml"]);
}

#[test]
fn output_in_missing_directory_is_an_io_error() {
    let dir = tempfile::tempdir().unwrap();
    for name in ["a.ply", "a.obj", "a.xml"] {
        let path = dir.path().join("missing").join(name);
        let e = create_mesh_sink(&path, None, &meta()).err().unwrap();
        assert!(
            matches!(&e, Error::Write { path: p, .. } if p == &path),
            "{e}"
        );
    }
}

#[test]
fn overwrites_existing_output_only_on_finish() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("a.ply");
    std::fs::write(&path, b"old").unwrap();
    let mut sink = create_mesh_sink(&path, None, &meta()).unwrap();
    sink.vertex([0.0; 3]).unwrap();
    assert_eq!(std::fs::read(&path).unwrap(), b"old");
    sink.finish().unwrap();
    assert_eq!(read_ply(&path).unwrap().0, vec![[0.0; 3]]);
}
