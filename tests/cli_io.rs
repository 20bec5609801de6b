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
