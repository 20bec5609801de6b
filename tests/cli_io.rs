//! The `tin` and `check` commands end to end: success, a bad input line, a bad output path.

use std::path::Path;
use std::process::{Command, Output};

fn sweeptin(args: &[&std::ffi::OsStr]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_sweeptin"))
        .args(args)
        .output()
        .unwrap()
}

fn run(args: &[&str]) -> Output {
    let a: Vec<&std::ffi::OsStr> = args.iter().map(std::ffi::OsStr::new).collect();
    sweeptin(&a)
}

fn stderr(o: &Output) -> String {
    String::from_utf8_lossy(&o.stderr).into_owned()
}

fn names(dir: &Path) -> Vec<String> {
    let mut v: Vec<String> = std::fs::read_dir(dir)
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .collect();
    v.sort();
    v
}

/// A small point cloud with a header line, a comment and mixed separators.
fn write_points(path: &Path) {
    let mut s = String::from("# test points\nx,y,z\n");
    let mut r = 12345u64;
    for i in 0..200 {
        r ^= r << 13;
        r ^= r >> 7;
        r ^= r << 17;
        let x = 511_000.0 + (r % 10_000) as f64 / 100.0;
        let y = 122_000.0 + ((r >> 20) % 10_000) as f64 / 100.0;
        let sep = if i % 2 == 0 { "," } else { " " };
        s.push_str(&format!("{x}{sep}{y}{sep}{}\n", 250.0 + i as f64 * 0.01));
    }
    std::fs::write(path, s).unwrap();
}

#[test]
fn tin_then_check_succeeds_for_every_format() {
    let dir = tempfile::tempdir().unwrap();
    let input = dir.path().join("pts.xyz");
    write_points(&input);
    for name in ["out.ply", "out.obj", "out.xml"] {
        let out = dir.path().join(name);
        let o = run(&[
            "tin",
            input.to_str().unwrap(),
            "-o",
            out.to_str().unwrap(),
            "--crs",
            "EPSG:3794",
        ]);
        let err = stderr(&o);
        assert!(o.status.success(), "{name}: {err}");
        assert_eq!(err.lines().count(), 1, "one summary line: {err}");
        assert!(
            err.contains("200 points") && err.contains("triangles"),
            "{err}"
        );
        assert!(out.exists());
    }
    let (v, t) = sweeptin::input::read_ply(dir.path().join("out.ply")).unwrap();
    assert_eq!(v.len(), 200);
    assert!(t.len() > 300);
    assert_eq!(
        names(dir.path()),
        ["out.obj", "out.ply", "out.xml", "pts.xyz"]
    );

    let ply = dir.path().join("out.ply");
    let o = run(&["check", ply.to_str().unwrap()]);
    assert!(o.status.success(), "{}", stderr(&o));
    let stdout = String::from_utf8_lossy(&o.stdout);
    assert!(stdout.contains("valid (200 vertices"), "{stdout}");
}

#[test]
fn bad_xyz_line_exit_3_names_file_and_line_and_leaves_nothing() {
    let dir = tempfile::tempdir().unwrap();
    let input = dir.path().join("bad.xyz");
    std::fs::write(&input, "x y z\n0 0 0\n1 0 0\n0 1 zero\n1 1 1\n").unwrap();
    let out = dir.path().join("out.ply");
    let o = run(&["tin", input.to_str().unwrap(), "-o", out.to_str().unwrap()]);
    assert_eq!(o.status.code(), Some(3));
    let err = stderr(&o);
    assert!(err.contains("bad.xyz:4:"), "{err}");
    assert!(err.contains("\"zero\""), "{err}");
    assert_eq!(
        names(dir.path()),
        ["bad.xyz"],
        "no output and no temporary file"
    );
}

#[test]
fn output_to_missing_directory_exit_4() {
    let dir = tempfile::tempdir().unwrap();
    let input = dir.path().join("pts.xyz");
    write_points(&input);
    let out = dir.path().join("no-such-dir").join("out.ply");
    let o = run(&["tin", input.to_str().unwrap(), "-o", out.to_str().unwrap()]);
    assert_eq!(o.status.code(), Some(4));
    let err = stderr(&o);
    assert!(err.contains("no-such-dir/out.ply"), "{err}");
    assert_eq!(names(dir.path()), ["pts.xyz"]);
}

#[test]
fn unknown_output_extension_exit_2() {
    let dir = tempfile::tempdir().unwrap();
    let input = dir.path().join("pts.xyz");
    write_points(&input);
    let out = dir.path().join("out.stl");
    let o = run(&["tin", input.to_str().unwrap(), "-o", out.to_str().unwrap()]);
    assert_eq!(o.status.code(), Some(2));
    assert!(stderr(&o).contains("unknown mesh format"), "{}", stderr(&o));
    assert_eq!(names(dir.path()), ["pts.xyz"]);
}

#[test]
fn check_on_damaged_ply_exit_3() {
    let dir = tempfile::tempdir().unwrap();
    let ply = dir.path().join("broken.ply");
    std::fs::write(
        &ply,
        "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\n\
         property float z\nelement face 1\nproperty list uchar int vertex_indices\nend_header\n\
         0 0 0\n1 0 0\n0 1 0\n4 0 1 2 0\n",
    )
    .unwrap();
    let o = run(&["check", ply.to_str().unwrap()]);
    assert_eq!(o.status.code(), Some(3));
    let err = stderr(&o);
    assert!(
        err.contains("broken.ply") && err.contains("only triangles"),
        "{err}"
    );
}

/// An edit of a binary PLY's bytes: the data's offset, its vertices and triangles.
type Edit = dyn Fn(&mut Vec<u8>, usize, &[[f64; 3]], &[[u32; 3]]);

/// The byte offset of a binary PLY's data (after `end_header\n`).
fn data_start(bytes: &[u8]) -> usize {
    bytes
        .windows(11)
        .position(|w| w == b"end_header\n")
        .unwrap()
        + 11
}

/// Issue 41, item 14: `check` rejected the tool's own outputs unless told how they were made
/// (`--breaklines`, `--trimmed`, `--not-delaunay`): refine with breaklines, simplify windows,
/// `thin --tile`, `--clip-breaklines`. Each output says what it is (a PLY `comment sweeptin:
/// …`, the `.stin` header's flags) and `sweeptin check OUT` passes on every mesh the tool
/// writes; a flipped edge or a moved vertex still fails.
#[test]
fn check_passes_every_mesh_the_tool_writes_and_fails_on_damage() {
    let dir = tempfile::tempdir().unwrap();
    let d = |n: &str| dir.path().join(n).to_str().unwrap().to_string();
    let sample = Path::new(env!("CARGO_MANIFEST_DIR")).join("data/sample/startinpy_small.laz");
    let s = sample.to_str().unwrap();
    // Lines inside the points (heights from them), one running out of them (clipped), and a
    // boundary polygon.
    std::fs::write(
        d("lines.txt"),
        "85710 447210\n85730 447235\n\n85712 447232\n85728 447212\n",
    )
    .unwrap();
    std::fs::write(d("long.txt"), "85690 447220\n85750 447220\n").unwrap();
    std::fs::write(
        d("bnd.geojson"),
        r#"{"type":"Polygon","coordinates":[[[85710,447210],[85730,447212],[85729,447235],[85711,447233],[85710,447210]]]}"#,
    )
    .unwrap();
    let mut grid = String::from("ncols 40\nnrows 30\nxllcorner 1000\nyllcorner 2000\n");
    grid.push_str("cellsize 1\nNODATA_value -9999\n");
    for r in 0..30 {
        let row: Vec<String> = (0..40)
            .map(|c| match (r > 20 && c < 6, (r * 7 + c * 3) % 11) {
                (true, _) => "-9999".into(),
                (_, k) => format!("{:.2}", (c as f64 / 5.0).sin() * 3.0 + k as f64 * 0.1),
            })
            .collect();
        grid.push_str(&row.join(" "));
        grid.push('\n');
    }
    std::fs::write(d("grid.asc"), grid).unwrap();
    let (l, long, bnd, g) = (
        d("lines.txt"),
        d("long.txt"),
        d("bnd.geojson"),
        d("grid.asc"),
    );
    let outputs: Vec<(&str, Vec<&str>)> = vec![
        ("tin.ply", vec!["tin", s]),
        ("tin.stin", vec!["tin", s]),
        ("lines.ply", vec!["tin", s, "--breaklines", &l]),
        ("lines.stin", vec!["tin", s, "--breaklines", &l]),
        (
            "clip.ply",
            vec!["tin", s, "--breaklines", &long, "--clip-breaklines"],
        ),
        ("boundary.ply", vec!["tin", s, "--trim-boundary", &bnd]),
        ("maxedge.stin", vec!["tin", s, "--max-edge", "1"]),
        ("flat.ply", vec!["tin", s, "--no-flat-triangles"]),
        ("products.ply", vec!["products", s, "--mesh"]),
        (
            "thin.ply",
            vec!["thin", s, "--max-error", "0.1", "--breaklines", &l],
        ),
        (
            "tiles.ply",
            vec!["thin", s, "--max-error", "0.1", "--tile", "5"],
        ),
        (
            "tiles.stin",
            vec!["thin", s, "--max-error", "0.1", "--tile", "5"],
        ),
        ("refine.ply", vec!["refine", s, "--max-area", "4"]),
        ("refinebl.ply", vec!["refine", s, "--breaklines", &l]),
        (
            "refinebnd.ply",
            vec!["refine", s, "--boundary", &bnd, "--breaklines", &l],
        ),
        ("simplify.ply", vec!["simplify", &g, "--max-error", "0.2"]),
        (
            "windows.ply",
            vec!["simplify", &g, "--max-error", "0.2", "--window", "8"],
        ),
        (
            "windows.stin",
            vec!["simplify", &g, "--max-error", "0.2", "--window", "8"],
        ),
    ];
    for (name, args) in &outputs {
        let out = d(name);
        let mut a = args.clone();
        if a[0] == "products" {
            a.push(&out);
        } else {
            a.extend(["-o", &out]);
        }
        a.push("-q");
        let o = run(&a);
        assert!(o.status.success(), "{name}: {}", stderr(&o));
        let o = run(&["check", &out]);
        assert!(o.status.success(), "check {name}: {}", stderr(&o));
        if name.ends_with(".ply") {
            let bytes = std::fs::read(&out).unwrap();
            let head = &bytes[..data_start(&bytes)];
            assert!(head.is_ascii(), "{name}: {}", String::from_utf8_lossy(head));
        }
    }
    // What the files say.
    let says = |name: &str| {
        let o = run(&["check", &d(name)]);
        String::from_utf8_lossy(&o.stdout).into_owned()
    };
    assert!(!says("tin.ply").contains("; a "), "{}", says("tin.ply"));
    assert!(says("lines.ply").contains("a constrained mesh"));
    assert!(says("tiles.stin").contains("a trimmed not-delaunay mesh"));
    let kind = sweeptin::input::read_ply_kind(d("boundary.ply")).unwrap();
    assert!(
        kind.constrained && kind.trimmed && !kind.not_delaunay,
        "{kind:?}"
    );

    // Damage: an edge of the Delaunay TIN flipped (two faces rewritten in place, the header
    // kept), a vertex of the thinned tiles moved.
    let damaged = |from: &str, to: &str, edit: &Edit| {
        let (v, t) = sweeptin::input::read_ply(d(from)).unwrap();
        let mut bytes = std::fs::read(d(from)).unwrap();
        let start = data_start(&bytes);
        edit(&mut bytes, start, &v, &t);
        std::fs::write(d(to), bytes).unwrap();
        let o = run(&["check", &d(to)]);
        assert_eq!(o.status.code(), Some(3), "{to}: {}", stderr(&o));
        stderr(&o)
    };
    let flip = |bytes: &mut Vec<u8>, start: usize, v: &[[f64; 3]], t: &[[u32; 3]]| {
        let face = |i: usize| start + v.len() * 24 + i * 13 + 1;
        let cross = |a: [f64; 3], b: [f64; 3], c: [f64; 3]| {
            (b[0] - a[0]) * (c[1] - a[1]) - (b[1] - a[1]) * (c[0] - a[0])
        };
        let mut by_edge = std::collections::HashMap::new();
        for (i, tri) in t.iter().enumerate() {
            for k in 0..3 {
                by_edge.insert((tri[k], tri[(k + 1) % 3]), (i, tri[(k + 2) % 3]));
            }
        }
        // The first interior edge whose quadrilateral is strictly convex.
        for (i, tri) in t.iter().enumerate() {
            for k in 0..3 {
                let (a, b, c) = (tri[k], tri[(k + 1) % 3], tri[(k + 2) % 3]);
                let Some(&(j, d)) = by_edge.get(&(b, a)) else {
                    continue;
                };
                let p = |x: u32| v[x as usize];
                if cross(p(c), p(a), p(d)) > 0.0 && cross(p(d), p(b), p(c)) > 0.0 {
                    for (f, tri) in [(i, [c, a, d]), (j, [d, b, c])] {
                        for (n, x) in tri.iter().enumerate() {
                            let at = face(f) + 4 * n;
                            bytes[at..at + 4].copy_from_slice(&x.to_le_bytes());
                        }
                    }
                    return;
                }
            }
        }
        panic!("no edge to flip");
    };
    let err = damaged("tin.ply", "flipped.ply", &flip);
    assert!(err.contains("not locally Delaunay"), "{err}");
    let moved = |bytes: &mut Vec<u8>, start: usize, v: &[[f64; 3]], _: &[[u32; 3]]| {
        // The middle vertex, moved 30 units east: its triangles fold.
        let i = v.len() / 2;
        let x = v[i][0] + 30.0;
        bytes[start + i * 24..start + i * 24 + 8].copy_from_slice(&x.to_le_bytes());
    };
    let err = damaged("tiles.ply", "moved.ply", &moved);
    assert!(err.contains("clockwise") || err.contains("twice"), "{err}");
    damaged("tin.ply", "moved_tin.ply", &moved);
}
