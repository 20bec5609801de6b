//! The LAS/LAZ point writer (`output::las::rewrite_points`): an identity rewrite keeps every
//! point, header field, VLR and EVLR (checked by laspy, an independent reader), class edits
//! are seen by laspy, LAS versions 1.0–1.4 and point formats 0/1/3/6/7/8 with extra bytes
//! round-trip, LAS ↔ LAZ convert, and no output is left on a refusal or an error.

use crate::data;

use std::path::{Path, PathBuf};
use std::process::Command;
use sweeptin::output::las::{PointEdit, rewrite_points};

/// Every LAS/LAZ file of tests/data.
fn all_files() -> Vec<PathBuf> {
    let mut v = Vec::new();
    let mut dirs = vec![data::data_dir()];
    while let Some(d) = dirs.pop() {
        for e in std::fs::read_dir(d).unwrap() {
            let p = e.unwrap().path();
            if p.is_dir() {
                dirs.push(p);
            } else if p
                .extension()
                .is_some_and(|e| e.eq_ignore_ascii_case("las") || e.eq_ignore_ascii_case("laz"))
            {
                v.push(p);
            }
        }
    }
    v.sort();
    v
}

/// Compares pairs of files with laspy: every header field that must be kept, every VLR and
/// EVLR (the LASzip VLR and COPC's `copc` records aside: they describe the encoding), every
/// dimension of every point. `CLASS` lines name pairs whose classification differs as
/// `expected` says (the rest equal). Prints "ok" per pair or raises.
const COMPARE: &str = r#"
import sys, json, laspy, numpy as np
def records(vs):
    return [(v.user_id, v.record_id, v.description, bytes(v.record_data_bytes()) if hasattr(v, 'record_data_bytes') else None)
            for v in (vs or []) if v.user_id not in ('laszip encoded', 'copc')]
for line in sys.stdin:
    job = json.loads(line)
    a, b = laspy.read(job['input']), laspy.read(job['output'])
    ha, hb = a.header, b.header
    for f in ['version', 'file_source_id', 'global_encoding', 'uuid', 'system_identifier',
              'generating_software', 'creation_date', 'scales', 'offsets', 'mins', 'maxs',
              'point_count', 'number_of_points_by_return']:
        va, vb = getattr(ha, f), getattr(hb, f)
        if f == 'global_encoding':
            va, vb = va.value, vb.value
        assert np.array_equal(np.asarray(va), np.asarray(vb)) if isinstance(va, np.ndarray) else va == vb, (job, f, va, vb)
    assert ha.point_format.id == hb.point_format.id, job
    assert hb.point_format.size == ha.point_format.size + 8 * len(job.get('added', [])), job
    assert records(ha.vlrs) == records(hb.vlrs) or job.get('added'), (job, records(ha.vlrs), records(hb.vlrs))
    assert records(ha.evlrs) == records(hb.evlrs), job
    assert list(ha.point_format.extra_dimension_names) + job.get('added', []) == list(hb.point_format.extra_dimension_names), job
    for d in ha.point_format.dimension_names:
        x, y = np.asarray(a[d]), np.asarray(b[d])
        if d == 'classification' and job.get('class') == 'every3':
            x = x.copy(); x[::3] = 2
        assert np.array_equal(x, y), (job, d)
    print('ok', flush=True)
"#;

/// Runs [`COMPARE`] on `jobs` (JSON lines); panics on any difference.
fn laspy_compare(jobs: &[String]) {
    let mut child = Command::new("python3")
        .args(["-c", COMPARE])
        .stdin(std::process::Stdio::piped())
        .stdout(std::process::Stdio::piped())
        .stderr(std::process::Stdio::piped())
        .spawn()
        .unwrap();
    {
        use std::io::Write;
        let mut stdin = child.stdin.take().unwrap();
        for j in jobs {
            writeln!(stdin, "{j}").unwrap();
        }
    }
    let o = child.wait_with_output().unwrap();
    let out = String::from_utf8_lossy(&o.stdout);
    assert!(
        o.status.success() && out.lines().count() == jobs.len(),
        "laspy found a difference:\n{}\n{}",
        out,
        String::from_utf8_lossy(&o.stderr)
    );
}

fn job(input: &Path, output: &Path, extra: &str) -> String {
    format!(
        r#"{{"input": {:?}, "output": {:?}{extra}}}"#,
        input.to_str().unwrap(),
        output.to_str().unwrap()
    )
}

fn keep(_: &mut PointEdit<'_>) -> sweeptin::Result<()> {
    Ok(())
}

/// An identity rewrite of every LAS/LAZ in tests/data (LAZ → LAZ, LAS → LAS, and each
/// converted to the other) keeps every point, header field, VLR and EVLR; LAS → LAS is the
/// input byte for byte.
#[test]
fn identity_rewrite_keeps_every_file_point_for_point() {
    let test = "identity_rewrite_keeps_every_file_point_for_point";
    if !data::python(&["laspy", "lazrs"], test) {
        return;
    }
    let dir = tempfile::tempdir().unwrap();
    let mut jobs = Vec::new();
    for (k, f) in all_files().iter().enumerate() {
        let laz = f.extension().unwrap() == "laz";
        let same = dir
            .path()
            .join(format!("{k}.{}", if laz { "laz" } else { "las" }));
        let other = dir
            .path()
            .join(format!("{k}x.{}", if laz { "las" } else { "laz" }));
        let s = rewrite_points(f, &same, &mut keep).unwrap();
        assert_eq!((s.changed, s.compressed), (0, laz));
        assert_eq!(s.bytes, std::fs::metadata(&same).unwrap().len());
        let c = rewrite_points(f, &other, &mut keep).unwrap();
        assert_eq!(c.points, s.points);
        for o in [&same, &other] {
            let info = sweeptin::input::las::FileInfo::read(o).unwrap();
            assert_eq!(info.point_count, s.points, "{}", o.display());
        }
        if !laz {
            assert!(
                std::fs::read(f).unwrap() == std::fs::read(&same).unwrap(),
                "{}: LAS → LAS is not byte for byte",
                f.display()
            );
        }
        if f.to_string_lossy().contains("copc") {
            assert!(
                s.notes.iter().any(|n| n.contains("plain LAZ")),
                "{:?}",
                s.notes
            );
        }
        jobs.push(job(f, &same, ""));
        jobs.push(job(f, &other, ""));
    }
    assert!(jobs.len() >= 2 * 19, "{} files", jobs.len() / 2);
    laspy_compare(&jobs);
}

/// Writes small files with laspy: LAS 1.0 (a 1.1 file relabelled: laspy writes no 1.0), 1.2,
/// 1.3 and 1.4, point formats 0, 1, 3, 6, 7, 8, with extra bytes and the classification flags
/// set, at UTM-sized offsets.
fn make_small_files(dir: &Path) -> Vec<PathBuf> {
    let script = r#"
import sys, laspy, numpy as np
d = sys.argv[1]
rng = np.random.default_rng(7)
for name, version, fmt in [('v10_f0', '1.1', 0), ('v12_f1', '1.2', 1), ('v12_f3', '1.2', 3),
                           ('v13_f1', '1.3', 1), ('v14_f6', '1.4', 6), ('v14_f7', '1.4', 7),
                           ('v14_f8', '1.4', 8)]:
    h = laspy.LasHeader(version=version, point_format=fmt)
    h.offsets = [500000.0, 5000000.0, 100.0]
    h.scales = [0.001, 0.001, 0.01]
    h.system_identifier = 'test system'
    h.generating_software = 'laspy test'
    h.add_extra_dim(laspy.ExtraBytesParams(name='Amplitude', type=np.float32))
    h.add_extra_dim(laspy.ExtraBytesParams(name='Deviation', type=np.uint16))
    n = 1001
    las = laspy.LasData(h)
    las.x = 500000 + rng.uniform(0, 100, n)
    las.y = 5000000 + rng.uniform(0, 100, n)
    las.z = 100 + rng.uniform(0, 30, n)
    las.intensity = rng.integers(0, 65535, n)
    las.return_number = rng.integers(1, 4, n)
    las.number_of_returns = np.maximum(las.return_number, rng.integers(1, 4, n))
    las.classification = rng.integers(0, 20, n)
    las.synthetic = rng.integers(0, 2, n).astype(bool)
    las.key_point = rng.integers(0, 2, n).astype(bool)
    las.withheld = rng.integers(0, 2, n).astype(bool)
    if fmt >= 6:
        las.overlap = rng.integers(0, 2, n).astype(bool)
    if 'gps_time' in las.point_format.dimension_names:
        las.gps_time = rng.uniform(0, 1e6, n)
    if 'red' in las.point_format.dimension_names:
        las.red = rng.integers(0, 65535, n)
    las.Amplitude = rng.uniform(-5, 5, n).astype(np.float32)
    las.Deviation = rng.integers(0, 100, n)
    las.write(f'{d}/{name}.las')
    las.write(f'{d}/{name}.laz')
b = bytearray(open(f'{d}/v10_f0.las', 'rb').read()); b[25] = 0
open(f'{d}/v10_f0.las', 'wb').write(b)
"#;
    let o = Command::new("python3")
        .args(["-c", script])
        .arg(dir)
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let mut v: Vec<PathBuf> = std::fs::read_dir(dir)
        .unwrap()
        .map(|e| e.unwrap().path())
        .collect();
    v.sort();
    v
}

/// Class edits (every third point becomes ground) in LAS 1.0–1.4, formats 0/1/3/6/7/8 with
/// extra bytes, LAS and LAZ, to either encoding: laspy sees the new classes and every other
/// dimension unchanged (the synthetic, key-point and withheld flags that share the class byte
/// in formats 0–5 included).
#[test]
fn class_edits_are_seen_by_laspy_in_every_version_and_format() {
    let test = "class_edits_are_seen_by_laspy_in_every_version_and_format";
    if !data::python(&["laspy", "lazrs"], test) {
        return;
    }
    let dir = tempfile::tempdir().unwrap();
    let src = dir.path().join("src");
    std::fs::create_dir(&src).unwrap();
    let files = make_small_files(&src);
    assert_eq!(files.len(), 14);
    let mut jobs = Vec::new();
    for (k, f) in files.iter().enumerate() {
        for ext in ["las", "laz"] {
            let out = dir.path().join(format!("{k}.{ext}"));
            let s = rewrite_points(f, &out, &mut |p| {
                if p.index() % 3 == 0 {
                    p.set_classification(2);
                }
                Ok(())
            })
            .unwrap();
            assert_eq!(s.points, 1001);
            assert!(s.changed > 250 && s.changed <= 334, "{}", s.changed);
            jobs.push(job(f, &out, r#", "class": "every3""#));
        }
    }
    laspy_compare(&jobs);
}

/// A class above 31 does not fit point formats 0–5: the rewrite fails naming the point, and
/// leaves nothing; formats 6–10 take it.
#[test]
fn a_class_above_31_in_formats_0_to_5_is_refused() {
    let dir = tempfile::tempdir().unwrap();
    let src = data::shared("lidar/lidR_Topography.laz");
    let out = dir.path().join("o.laz");
    let e = rewrite_points(&src, &out, &mut |p| {
        p.set_classification(40);
        Ok(())
    })
    .unwrap_err();
    assert!(e.to_string().contains("class 40"), "{e}");
    assert_eq!(e.kind().exit_code(), 2);
    assert_eq!(std::fs::read_dir(dir.path()).unwrap().count(), 0);
    let f6 = data::shared("lidar/ign_test_semis_2023_0300_6802_LA93_IGN69.laz");
    let s = rewrite_points(&f6, &out, &mut |p| {
        p.set_classification(40);
        Ok(())
    })
    .unwrap();
    assert_eq!(s.changed, s.points);
}

/// The editor's error midway leaves no output (and no temporary file); an existing output is
/// left as it was.
#[test]
fn an_editor_error_midway_leaves_no_output() {
    let dir = tempfile::tempdir().unwrap();
    let src = data::shared("lidar/arso_TM_511_122_sw_250m.laz");
    for name in ["o.laz", "o.las"] {
        let out = dir.path().join(name);
        let e = rewrite_points(&src, &out, &mut |p| match p.index() {
            500_000 => Err(sweeptin::Error::Options("stop here".into())),
            _ => Ok(()),
        })
        .unwrap_err();
        assert!(e.to_string().contains("stop here"));
        assert_eq!(std::fs::read_dir(dir.path()).unwrap().count(), 0, "{name}");
    }
    let out = dir.path().join("kept.laz");
    std::fs::write(&out, b"old").unwrap();
    let _ = rewrite_points(&src, &out, &mut |_| {
        Err(sweeptin::Error::Options("no".into()))
    })
    .unwrap_err();
    assert_eq!(std::fs::read(&out).unwrap(), b"old");
    assert_eq!(std::fs::read_dir(dir.path()).unwrap().count(), 1);
}

/// The output is never the input (by name or through a link), a symbolic link, a FIFO or a
/// directory: refused before anything is read, the input untouched.
#[test]
#[cfg(unix)]
fn the_writer_refuses_the_input_a_symlink_and_a_fifo() {
    let dir = tempfile::tempdir().unwrap();
    let src = dir.path().join("in.laz");
    std::fs::copy(data::shared("lidar/lidR_Topography.laz"), &src).unwrap();
    let before = std::fs::read(&src).unwrap();
    let status = |p: &Path| {
        rewrite_points(&src, p, &mut keep)
            .unwrap_err()
            .kind()
            .exit_code()
    };
    assert_eq!(status(&src), 2, "the input itself");
    let hard = dir.path().join("hard.laz");
    std::fs::hard_link(&src, &hard).unwrap();
    assert_eq!(status(&hard), 2, "a hard link to the input");
    let link = dir.path().join("link.laz");
    std::os::unix::fs::symlink(&src, &link).unwrap();
    assert_eq!(status(&link), 4, "a symbolic link");
    let elsewhere = dir.path().join("elsewhere.laz");
    let link2 = dir.path().join("link2.laz");
    std::os::unix::fs::symlink(&elsewhere, &link2).unwrap();
    assert_eq!(status(&link2), 4, "a dangling symbolic link");
    assert!(!elsewhere.exists());
    let fifo = dir.path().join("fifo.laz");
    assert!(
        Command::new("mkfifo")
            .arg(&fifo)
            .status()
            .unwrap()
            .success()
    );
    assert_eq!(status(&fifo), 4, "a FIFO");
    assert_eq!(status(dir.path()), 4, "a directory");
    assert!(std::fs::read(&src).unwrap() == before);
}
