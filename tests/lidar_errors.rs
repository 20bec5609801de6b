//! LAS/LAZ input on small files written here: filters and multi-file rules on known points, and
//! damaged files (empty, wrong format, truncated, corrupt), which must give clear errors and
//! never a panic.

use las::point::{Classification, Format};
use las::{Builder, Point, Transform, Vector, Version, Writer};
use std::path::{Path, PathBuf};
use sweeptin::Error;
use sweeptin::input::las::{FileInfo, Filter, LidarPoint, LidarReader, Returns};

/// A point to write: real-world coordinates, class, withheld flag, return number / count.
#[derive(Clone, Copy)]
struct P {
    xyz: [f64; 3],
    class: u8,
    withheld: bool,
    ret: (u8, u8),
}

fn p(x: f64, y: f64, z: f64) -> P {
    P {
        xyz: [x, y, z],
        class: 2,
        withheld: false,
        ret: (1, 1),
    }
}

/// Writes a LAS (or LAZ, by extension) file with the given point format, scale and offset.
fn write_cloud(path: &Path, format: u8, scale: [f64; 3], offset: [f64; 3], points: &[P]) {
    let mut b = Builder::from(if format >= 6 {
        Version::new(1, 4)
    } else {
        Version::new(1, 2)
    });
    b.point_format = Format::new(format).unwrap();
    b.transforms = Vector {
        x: Transform {
            scale: scale[0],
            offset: offset[0],
        },
        y: Transform {
            scale: scale[1],
            offset: offset[1],
        },
        z: Transform {
            scale: scale[2],
            offset: offset[2],
        },
    };
    let mut header = b.into_header().unwrap();
    if format >= 6 {
        header
            .set_wkt_crs(br#"PROJCS["test",AUTHORITY["EPSG","2154"]]"#.to_vec())
            .unwrap();
    }
    let fmt = *header.point_format();
    let mut w = Writer::from_path(path, header).unwrap();
    for q in points {
        w.write_point(Point {
            x: q.xyz[0],
            y: q.xyz[1],
            z: q.xyz[2],
            classification: Classification::new(q.class).unwrap(),
            is_withheld: q.withheld,
            return_number: q.ret.0,
            number_of_returns: q.ret.1,
            gps_time: fmt.has_gps_time.then_some(1.0),
            color: fmt.has_color.then(Default::default),
            nir: fmt.has_nir.then_some(0),
            ..Default::default()
        })
        .unwrap();
    }
    w.close().unwrap();
}

/// `n` points on a jittered grid with varied classes and returns.
fn grid(n: usize) -> Vec<P> {
    (0..n)
        .map(|i| {
            let (x, y) = ((i % 40) as f64, (i / 40) as f64);
            P {
                xyz: [
                    1000.0 + x * 0.5,
                    2000.0 + y * 0.5,
                    10.0 + ((i * 7) % 13) as f64 * 0.1,
                ],
                class: [1, 2, 2, 6, 9][i % 5],
                withheld: i % 17 == 0,
                ret: [(1, 1), (1, 2), (2, 2), (1, 3), (3, 3)][i % 5],
            }
        })
        .collect()
}

fn format_message(e: &Error, path: &Path) -> String {
    match e {
        Error::Format { path: p, message } => {
            assert_eq!(p, path);
            message.clone()
        }
        other => panic!("expected a format error for {path:?}, got {other:?}"),
    }
}

fn open_err(path: &Path) -> String {
    let e = LidarReader::open(&[path], &Filter::default()).unwrap_err();
    let msg = format_message(&e, path);
    // The info path gives the same error.
    let e2 = FileInfo::read(path).unwrap_err();
    assert_eq!(format_message(&e2, path), msg);
    msg
}

/// Opens and reads everything; returns the error, if any. Must never panic.
fn try_read(path: &Path, parallel: bool) -> Result<usize, Error> {
    let options = sweeptin::input::las::ReadOptions {
        parallel,
        batch_points: 300,
        ..Default::default()
    };
    let mut r = LidarReader::open_with(&[path], &Filter::keep_all(), options)?;
    Ok(r.read_all()?.len())
}

fn tmp() -> tempfile::TempDir {
    tempfile::tempdir().unwrap()
}

#[test]
fn written_points_come_back_exactly_las_and_laz() {
    let dir = tmp();
    let pts = grid(1000);
    for (name, format) in [
        ("a.las", 1),
        ("a.laz", 1),
        ("b.laz", 6),
        ("c.laz", 8),
        ("d.las", 0),
    ] {
        let path = dir.path().join(name);
        write_cloud(&path, format, [0.01; 3], [1000.0, 2000.0, 0.0], &pts);
        for parallel in [true, false] {
            let options = sweeptin::input::las::ReadOptions {
                parallel,
                batch_points: 333,
                ..Default::default()
            };
            let mut r = LidarReader::open_with(&[&path], &Filter::keep_all(), options).unwrap();
            let got = r.read_all().unwrap();
            assert_eq!(got.len(), pts.len(), "{name}");
            for (i, (g, w)) in got.iter().zip(&pts).enumerate() {
                assert_eq!(g.index, i as u64);
                let world = [g.x, g.y, g.z];
                assert!(
                    (0..3).all(|a| (world[a] - w.xyz[a]).abs() < 1e-9),
                    "{name} {i}"
                );
                assert_eq!(g.classification, w.class);
                assert_eq!((g.return_number, g.number_of_returns), w.ret);
                assert_eq!(g.flags & LidarPoint::WITHHELD != 0, w.withheld);
            }
        }
    }
}

#[test]
fn withheld_points_are_dropped_by_default_and_counted() {
    let dir = tmp();
    let path = dir.path().join("w.laz");
    let pts = grid(500);
    write_cloud(&path, 6, [0.01; 3], [0.0; 3], &pts);
    let withheld = pts.iter().filter(|q| q.withheld).count() as u64;
    let mut r = LidarReader::open(&[&path], &Filter::default()).unwrap();
    let got = r.read_all().unwrap();
    assert_eq!(got.len() as u64, 500 - withheld);
    assert_eq!(r.stats().withheld, withheld);
    assert_eq!(r.crs().and_then(|c| c.epsg), Some(2154));
    // First-return ground points, withheld kept: counts follow the documented filter order.
    let f = Filter {
        classes: Some(vec![2]),
        returns: Returns::First,
        drop_withheld: false,
        bbox: None,
        z_from: None,
        classes_from: None,
    };
    let mut r = LidarReader::open(&[&path], &f).unwrap();
    let got = r.read_all().unwrap();
    let want = pts.iter().filter(|q| q.class == 2 && q.ret.0 == 1).count();
    assert_eq!(got.len(), want);
    let s = *r.stats();
    assert_eq!(s.withheld, 0);
    assert_eq!(s.class, pts.iter().filter(|q| q.class != 2).count() as u64);
    assert_eq!(s.read, s.kept + s.withheld + s.class + s.returns + s.bbox);
}

/// Files with scales and offsets on no common lattice combine: every point gets the double
/// nearest its decimal value, whatever the encoding.
#[test]
fn different_scales_and_offsets_combine_exactly() {
    let dir = tmp();
    let a = dir.path().join("a.las");
    let b = dir.path().join("b.laz");
    let c = dir.path().join("c.las");
    let pa = [p(1000.01, 2000.02, 5.0), p(1000.5, 2000.5, 6.01)];
    let pb = [p(1001.234, 2001.001, 7.5), p(1001.0, 2001.0, 8.0)];
    let pc = [p(1.5, 1.0, 1.0)];
    write_cloud(&a, 1, [0.01; 3], [1000.0, 2000.0, 0.0], &pa);
    write_cloud(&b, 1, [0.001, 0.001, 0.5], [1000.5, 1999.999, 0.0], &pb);
    // 0.003 is no multiple of 0.01 nor the other way round: refused before, read now.
    write_cloud(&c, 1, [0.003, 0.01, 0.01], [0.0; 3], &pc);
    let mut r = LidarReader::open(&[&a, &b, &c], &Filter::default()).unwrap();
    let got = r.read_all().unwrap();
    let xyz: Vec<[f64; 3]> = got.iter().map(|g| [g.x, g.y, g.z]).collect();
    assert_eq!(
        xyz,
        [
            [1000.01, 2000.02, 5.0],
            [1000.5, 2000.5, 6.01],
            [1001.234, 2001.001, 7.5],
            [1001.0, 2001.0, 8.0],
            [1.5, 1.0, 1.0]
        ]
    );
    assert_eq!(
        got.iter().map(|g| g.index).collect::<Vec<_>>(),
        [0, 1, 2, 3, 4]
    );
}

#[test]
fn a_file_with_no_points_reads_as_empty() {
    let dir = tmp();
    for name in ["e.las", "e.laz"] {
        let path = dir.path().join(name);
        write_cloud(&path, 1, [0.01; 3], [0.0; 3], &[]);
        assert_eq!(FileInfo::read(&path).unwrap().point_count, 0);
        assert_eq!(try_read(&path, true).unwrap(), 0);
    }
}

#[test]
fn missing_file_and_no_files() {
    let dir = tmp();
    let path = dir.path().join("nope.laz");
    match LidarReader::open(&[&path], &Filter::default()).unwrap_err() {
        Error::Io { path: p, .. } => assert_eq!(p, path),
        other => panic!("{other:?}"),
    }
    let none: [PathBuf; 0] = [];
    assert!(matches!(
        LidarReader::open(&none, &Filter::default()),
        Err(Error::NoInput)
    ));
}

#[test]
fn empty_file() {
    let dir = tmp();
    let path = dir.path().join("empty.laz");
    std::fs::write(&path, b"").unwrap();
    assert!(open_err(&path).contains("empty"));
}

#[test]
fn text_file_named_laz() {
    let dir = tmp();
    let path = dir.path().join("notes.laz");
    std::fs::write(&path, "x,y,z\n1,2,3\n").unwrap();
    let msg = open_err(&path);
    assert!(
        msg.contains("not a LAS/LAZ file") && msg.contains("x,y,z"),
        "{msg}"
    );
    let tiny = dir.path().join("tiny.las");
    std::fs::write(&tiny, b"LA").unwrap();
    assert!(open_err(&tiny).contains("not a LAS/LAZ file"));
}

#[test]
fn truncated_files() {
    let dir = tmp();
    for name in ["t.las", "t.laz"] {
        let full = dir.path().join(name);
        write_cloud(&full, 6, [0.01; 3], [0.0; 3], &grid(3000));
        let bytes = std::fs::read(&full).unwrap();
        let cut = dir.path().join(format!("cut_{name}"));
        for len in [
            5,
            100,
            300,
            400,
            700,
            1000,
            bytes.len() / 2,
            bytes.len() - 9,
            bytes.len() - 1,
        ] {
            std::fs::write(&cut, &bytes[..len]).unwrap();
            let msg = open_err(&cut);
            assert!(msg.contains("truncated"), "{name} cut at {len}: {msg}");
        }
    }
}

#[test]
fn corrupt_header_fields() {
    let dir = tmp();
    let full = dir.path().join("h.las");
    write_cloud(&full, 1, [0.01; 3], [0.0; 3], &grid(100));
    let bytes = std::fs::read(&full).unwrap();
    let bad = dir.path().join("bad.las");
    let patch = |at: usize, new: &[u8]| {
        let mut b = bytes.clone();
        b[at..at + new.len()].copy_from_slice(new);
        std::fs::write(&bad, b).unwrap();
        open_err(&bad)
    };
    assert!(patch(24, &[2, 0]).contains("unsupported LAS version 2.0"));
    assert!(patch(131, &0f64.to_le_bytes()).contains("scale"));
    assert!(patch(155, &f64::NAN.to_le_bytes()).contains("offset"));
    assert!(patch(96, &u32::MAX.to_le_bytes()).contains("byte 4294967295"));
    assert!(patch(96, &10u32.to_le_bytes()).contains("smaller than the header size"));
    let m = patch(107, &u32::MAX.to_le_bytes());
    assert!(m.contains("truncated") && m.contains("4294967295"), "{m}");
    assert!(patch(104, &[42]).contains("invalid header"));
}

/// A LAZ file whose chunk table or point count is damaged fails before decompression.
#[test]
fn corrupt_laz_chunk_table_and_counts() {
    let dir = tmp();
    let full = dir.path().join("c.laz");
    write_cloud(&full, 1, [0.01; 3], [0.0; 3], &grid(3000));
    let bytes = std::fs::read(&full).unwrap();
    let data_start = u32::from_le_bytes(bytes[96..100].try_into().unwrap()) as usize;
    let table_at =
        i64::from_le_bytes(bytes[data_start..data_start + 8].try_into().unwrap()) as usize;
    let bad = dir.path().join("bad.laz");
    let write = |b: &[u8]| std::fs::write(&bad, b).unwrap();
    // Chunk table offset past the end.
    let mut b = bytes.clone();
    b[data_start..data_start + 8].copy_from_slice(&(bytes.len() as i64 + 100).to_le_bytes());
    write(&b);
    assert!(open_err(&bad).contains("past the end"));
    // An absurd number of chunks.
    let mut b = bytes.clone();
    b[table_at + 4..table_at + 8].copy_from_slice(&u32::MAX.to_le_bytes());
    write(&b);
    assert!(open_err(&bad).contains("chunks"));
    // More points announced than the chunks hold.
    let mut b = bytes.clone();
    b[107..111].copy_from_slice(&1_000_000u32.to_le_bytes());
    write(&b);
    assert!(open_err(&bad).contains("does not match"));
    // A layered (LAS 1.4, format 6) chunk whose first layer claims 4 GB: the decoder would
    // allocate it, so it is refused up front.
    let full6 = dir.path().join("c6.laz");
    write_cloud(&full6, 6, [0.01; 3], [0.0; 3], &grid(3000));
    let mut b = std::fs::read(&full6).unwrap();
    let data_start = u32::from_le_bytes(b[96..100].try_into().unwrap()) as usize;
    let first_layer = data_start + 8 + 30 + 4;
    b[first_layer..first_layer + 4].copy_from_slice(&u32::MAX.to_le_bytes());
    write(&b);
    let msg = open_err(&bad);
    assert!(msg.contains("chunk 0") && msg.contains("damaged"), "{msg}");
}

/// Damage past the header is found while reading; the reader then stops for good.
#[test]
fn damage_found_while_reading_stops_the_reader() {
    let dir = tmp();
    let full = dir.path().join("r.las");
    // Bigger than the reader's 1 MB read buffer.
    write_cloud(&full, 1, [0.01; 3], [0.0; 3], &grid(100_000));
    let ok = dir.path().join("ok.las");
    write_cloud(&ok, 1, [0.01; 3], [0.0; 3], &grid(10));
    let options = sweeptin::input::las::ReadOptions {
        parallel: false,
        batch_points: 1000,
        ..Default::default()
    };
    let mut r = LidarReader::open_with(&[&full, &ok], &Filter::keep_all(), options).unwrap();
    let mut out = Vec::new();
    assert_eq!(r.read_chunk(&mut out, 150).unwrap(), 150);
    // Truncate the file behind the reader's back.
    let bytes = std::fs::read(&full).unwrap();
    std::fs::write(&full, &bytes[..bytes.len() / 2]).unwrap();
    let e = loop {
        match r.read_chunk(&mut out, 10_000) {
            Ok(0) => panic!("the truncation went unnoticed"),
            Ok(_) => {}
            Err(e) => break e,
        }
    };
    assert!(format_message(&e, &full).contains("truncated"));
    assert_eq!(r.read_chunk(&mut out, 100).unwrap(), 0);
}

/// Deterministic byte mutations all over small LAS and LAZ files: every outcome is `Ok` or a
/// clean error, never a panic or an abort.
#[test]
fn mutated_files_never_panic() {
    let dir = tmp();
    let mut state = 0x2545F4914F6CDD1Du64;
    let mut next = move || {
        state ^= state << 13;
        state ^= state >> 7;
        state ^= state << 17;
        state
    };
    for (name, format) in [("m.las", 1), ("m.laz", 1), ("m6.laz", 6)] {
        let full = dir.path().join(name);
        write_cloud(&full, format, [0.01; 3], [0.0; 3], &grid(600));
        let bytes = std::fs::read(&full).unwrap();
        let bad = dir.path().join(format!("bad_{name}"));
        for round in 0..150 {
            let mut b = bytes.clone();
            for _ in 0..1 + round % 4 {
                let at = (next() % b.len() as u64) as usize;
                b[at] = next() as u8;
            }
            std::fs::write(&bad, &b).unwrap();
            match try_read(&bad, round % 2 == 0) {
                Ok(_) | Err(Error::Format { .. }) | Err(Error::Io { .. }) => {}
                Err(other) => panic!("{name} round {round}: unexpected error {other:?}"),
            }
        }
    }
}
