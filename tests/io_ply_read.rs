//! The PLY reader: encodings, property types and orders, errors, and arbitrary bytes.

use sweeptin::Error;
use sweeptin::input::ply::{Mesh, read_ply_from};

fn read(bytes: &[u8]) -> sweeptin::Result<Mesh> {
    read_ply_from(bytes, bytes.len() as u64, "t.ply")
}

fn format_message(bytes: &[u8]) -> String {
    match read(bytes) {
        Err(Error::Format { path, message }) => {
            assert_eq!(path.to_str(), Some("t.ply"));
            message
        }
        other => panic!("expected a format error, got {other:?}"),
    }
}

const ASCII: &str = "ply
format ascii 1.0
comment made by hand
element vertex 4
property float x
property float y
property float z
property uchar red
element face 2
property list uchar int vertex_indices
end_header
0 0 1.5 255
1 0 2 0
0.5 1 -3 7
1 1 0.1 9
3 0 1 2
3 2 1 3
";

#[test]
fn ascii() {
    let (v, t) = read(ASCII.as_bytes()).unwrap();
    assert_eq!(v.len(), 4);
    assert_eq!(v[0], [0.0, 0.0, 1.5]);
    assert_eq!(v[2], [0.5, 1.0, -3.0]);
    // A float property reads as the f32 nearest to the text, widened.
    assert_eq!(v[3][2], f64::from(0.1f32));
    assert_eq!(t, vec![[0, 1, 2], [2, 1, 3]]);
}

#[test]
fn ascii_with_crlf() {
    let text = ASCII.replace('\n', "\r\n");
    let (v, t) = read(text.as_bytes()).unwrap();
    assert_eq!((v.len(), t.len()), (4, 2));
}

/// A binary PLY with vertex properties in an unusual order and with extras, a face element with
/// an extra scalar before the list, and an extra element after.
fn binary(big: bool, vertex_index_name: &str) -> Vec<u8> {
    let fmt = if big {
        "binary_big_endian"
    } else {
        "binary_little_endian"
    };
    let header = format!(
        "ply\nformat {fmt} 1.0\nobj_info whatever\nelement vertex 3\nproperty double z\n\
         property float nx\nproperty list uchar float uv\nproperty double y\nproperty double x\n\
         element face 1\nproperty int flags\nproperty list ushort uint {vertex_index_name}\n\
         element edge 1\nproperty int vertex1\nproperty int vertex2\nend_header\n"
    );
    let mut b = header.into_bytes();
    macro_rules! put {
        ($v:expr) => {
            if big {
                b.extend_from_slice(&$v.to_be_bytes())
            } else {
                b.extend_from_slice(&$v.to_le_bytes())
            }
        };
    }
    for (x, y, z) in [
        (511_000.005f64, 122_000.015f64, 247.125f64),
        (1.0, 2.0, 3.0),
        (-1.0, 0.5, 0.0),
    ] {
        put!(z);
        put!(0.25f32);
        put!(2u8);
        put!(0.5f32);
        put!(0.75f32);
        put!(y);
        put!(x);
    }
    put!(-7i32);
    put!(3u16);
    put!(2u32);
    put!(0u32);
    put!(1u32);
    put!(0i32);
    put!(1i32);
    b
}

#[test]
fn binary_both_endians_any_property_order() {
    for big in [false, true] {
        for name in ["vertex_indices", "vertex_index"] {
            let (v, t) = read(&binary(big, name)).unwrap();
            assert_eq!(v[0], [511_000.005, 122_000.015, 247.125], "big={big}");
            assert_eq!(v[2], [-1.0, 0.5, 0.0]);
            assert_eq!(t, vec![[2, 0, 1]]);
        }
    }
}

#[test]
fn integer_list_types() {
    for (count, index) in [
        ("uchar", "int"),
        ("int", "uint"),
        ("uint", "int"),
        ("ushort", "int"),
    ] {
        let mut b = format!(
            "ply\nformat binary_little_endian 1.0\nelement vertex 3\nproperty float x\n\
             property float y\nproperty float z\nelement face 1\n\
             property list {count} {index} vertex_indices\nend_header\n"
        )
        .into_bytes();
        for p in [[0f32, 0., 0.], [1., 0., 0.], [0., 1., 0.]] {
            for c in p {
                b.extend_from_slice(&c.to_le_bytes());
            }
        }
        match count {
            "uchar" => b.push(3),
            "ushort" => b.extend_from_slice(&3u16.to_le_bytes()),
            _ => b.extend_from_slice(&3u32.to_le_bytes()),
        }
        for i in [0u32, 1, 2] {
            b.extend_from_slice(&i.to_le_bytes());
        }
        assert_eq!(read(&b).unwrap().1, vec![[0, 1, 2]], "{count} {index}");
    }
}

#[test]
fn clear_errors() {
    let cases: Vec<(Vec<u8>, &str)> = vec![
        (b"PK\x03\x04zipfile".to_vec(), "not a PLY file"),
        (b"".to_vec(), "not a PLY file"),
        (b"ply\nformat ascii 1.0\nelement vertex 1\n".to_vec(), "no end_header"),
        (b"ply\nformat utf16 1.0\nend_header\n".to_vec(), "unknown format"),
        (b"ply\nelement vertex 0\nend_header\n".to_vec(), "no format line"),
        (b"ply\nformat ascii 1.0\nelement vertex -1\nend_header\n".to_vec(), "bad element count"),
        (b"ply\nformat ascii 1.0\nproperty float x\nend_header\n".to_vec(), "before any element"),
        (
            b"ply\nformat ascii 1.0\nelement vertex 1\nproperty quad x\nend_header\n".to_vec(),
            "unknown type \"quad\"",
        ),
        (
            b"ply\nformat ascii 1.0\nelement vertex 1\nproperty float x\nproperty float y\nend_header\n1 2\n"
                .to_vec(),
            "no property \"z\"",
        ),
        (b"ply\nformat ascii 1.0\nelement face 0\nend_header\n".to_vec(), "no vertex element"),
        (ASCII.replace("3 2 1 3", "4 2 1 3 0").into_bytes(), "face 1: has 4 vertices; only triangles"),
        (ASCII.replace("3 2 1 3", "3 2 1 4").into_bytes(), "face 1: refers to vertex 4, but there are 4"),
        (ASCII.replace("3 2 1 3", "3 2 -1 3").into_bytes(), "face 1: refers to vertex -1"),
        (ASCII.replace("1 0 2 0", "1 zero 2 0").into_bytes(), "line 13: vertex 1: \"zero\" is not a valid F32"),
        (ASCII.replace("1 0 2 0", "1 0 nan 0").into_bytes(), "vertex 1: coordinate is not finite"),
        (ASCII.replace("1 0 2 0", "1 0 2 0 5").into_bytes(), "vertex 1: more values"),
        (ASCII.replace("1 0 2 0", "1 0 2 256").into_bytes(), "\"256\" is not a valid U8"),
        (ASCII.replace("3 2 1 3\n", "").into_bytes(), "face 1: truncated"),
        (
            ASCII.replace("int vertex_indices", "float vertex_indices").into_bytes(),
            "floating-point type",
        ),
        (
            ASCII.replace("property list uchar int vertex_indices", "property int n").into_bytes(),
            "no vertex_indices list",
        ),
    ];
    for (bytes, want) in cases {
        let m = format_message(&bytes);
        assert!(m.contains(want), "expected {want:?} in {m:?}");
    }
}

#[test]
fn truncated_binary_says_so() {
    let full = binary(false, "vertex_indices");
    let header_end = full.windows(11).position(|w| w == b"end_header\n").unwrap() + 11;
    for cut in header_end..full.len() {
        let m = format_message(&full[..cut]);
        assert!(m.contains("truncated"), "cut at {cut}: {m}");
    }
    let mut fixed =
        b"ply\nformat binary_little_endian 1.0\nelement vertex 1000000000\nproperty double x\n\
                  property double y\nproperty double z\nend_header\n"
            .to_vec();
    fixed.extend_from_slice(&[0u8; 48]);
    let m = format_message(&fixed);
    assert!(m.contains("announces 1000000000 vertex elements"), "{m}");
}

#[test]
fn too_many_vertices_for_u32() {
    let b = b"ply\nformat binary_little_endian 1.0\nelement vertex 4294967297\nproperty double x\n\
              property double y\nproperty double z\nend_header\n";
    assert!(format_message(b).contains("32-bit"));
}

fn rng(seed: u64) -> impl FnMut() -> u64 {
    let mut s = seed.wrapping_mul(0x9E37_79B9_7F4A_7C15) | 1;
    move || {
        s ^= s << 13;
        s ^= s >> 7;
        s ^= s << 17;
        s
    }
}

/// Arbitrary bytes never panic: truncations, byte flips and garbage in valid files of every
/// encoding, and pure noise after a plausible header start.
#[test]
fn fuzz_like_no_panics() {
    let seeds: Vec<Vec<u8>> = vec![
        ASCII.as_bytes().to_vec(),
        binary(false, "vertex_indices"),
        binary(true, "vertex_index"),
    ];
    let mut r = rng(42);
    let mut outcomes = [0usize; 2];
    for round in 0..3000 {
        let base = &seeds[round % seeds.len()];
        let mut b = base.clone();
        match r() % 4 {
            0 => b.truncate((r() % (b.len() as u64 + 1)) as usize),
            1 => {
                for _ in 0..1 + r() % 4 {
                    let i = (r() % b.len() as u64) as usize;
                    b[i] = r() as u8;
                }
            }
            2 => {
                let i = (r() % b.len() as u64) as usize;
                let junk: Vec<u8> = (0..r() % 16).map(|_| r() as u8).collect();
                b.splice(i..i, junk);
            }
            _ => {
                b = b"ply\n".to_vec();
                b.extend((0..r() % 200).map(|_| {
                    let c = r() as u8;
                    // mostly header-ish text so the parser gets past the first lines
                    const TEXT: &[u8] = b"format ascii binary_little_endian 1.0 element vertex face \
                        property list uchar int float double x y z vertex_indices end_header\n 0123456789-.";
                    if c < 200 { TEXT[c as usize % TEXT.len()] } else { c }
                }));
            }
        }
        // Also lie about the length.
        let len = if r().is_multiple_of(8) {
            r()
        } else {
            b.len() as u64
        };
        let result = read_ply_from(&b[..], len, "fuzz.ply");
        if let Ok((v, t)) = &result {
            for tri in t {
                assert!(tri.iter().all(|&i| (i as usize) < v.len()));
            }
        }
        outcomes[result.is_ok() as usize] += 1;
    }
    assert!(outcomes[0] > 0 && outcomes[1] > 0, "{outcomes:?}");
}
