//! "Real PLY that mesh tools open": a PLY written by sweeptin is read back with Python's `plyfile`
//! (install: `python3 -m pip install plyfile==1.1.5`). Without Python or the package the test
//! fails under `CI=true`; locally it prints SKIP and returns.

use crate::data;

use std::process::Command;
use sweeptin::output::{MeshMeta, create_mesh_sink};

const SCRIPT: &str = r#"
import sys
from plyfile import PlyData
ply = PlyData.read(sys.argv[1])
v = ply['vertex']
f = ply['face']
print("format", ply.text, ply.byte_order)
print("counts", v.count, f.count)
print("names", ",".join(p.name for p in v.properties))
for i in (0, 1, v.count - 1):
    print("v", i, repr(float(v['x'][i])), repr(float(v['y'][i])), repr(float(v['z'][i])))
for i in (0, f.count - 1):
    print("f", i, " ".join(str(int(k)) for k in f['vertex_indices'][i]))
for c in ply.comments:
    print("comment", c)
"#;

fn python_with_plyfile() -> Option<&'static str> {
    ["python3", "python"].into_iter().find(|py| {
        Command::new(py)
            .args(["-c", "import plyfile"])
            .output()
            .is_ok_and(|o| o.status.success())
    })
}

#[test]
fn plyfile_reads_our_ply() {
    let Some(python) = python_with_plyfile() else {
        assert!(
            !data::in_ci(),
            "plyfile_reads_our_ply: python3 with plyfile is required under CI=true"
        );
        eprintln!(
            "SKIP plyfile_reads_our_ply: python3 with the plyfile package not found \
             (python3 -m pip install plyfile==1.1.5)"
        );
        return;
    };
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("grid.ply");
    let meta = MeshMeta {
        crs: Some("EPSG:3794".into()),
        comments: vec!["hello from the test".into()],
    };
    let (nx, ny) = (30usize, 20usize);
    let mut verts = Vec::new();
    let mut sink = create_mesh_sink(&path, None, &meta).unwrap();
    let mut tris = Vec::new();
    for j in 0..ny {
        for i in 0..nx {
            let p = [
                511_000.005 + i as f64 * 0.1,
                122_000.015 + j as f64 / 3.0,
                247.125 + (i * j) as f64 * 1e-3,
            ];
            verts.push(p);
            sink.vertex(p).unwrap();
        }
        if j > 0 {
            for i in 0..nx - 1 {
                let a = ((j - 1) * nx + i) as u64;
                for t in [
                    [a, a + 1, a + nx as u64 + 1],
                    [a, a + nx as u64 + 1, a + nx as u64],
                ] {
                    sink.triangle(t).unwrap();
                    tris.push(t);
                }
            }
        }
    }
    sink.finish().unwrap();

    let out = Command::new(python)
        .arg("-c")
        .arg(SCRIPT)
        .arg(&path)
        .output()
        .unwrap();
    let stdout = String::from_utf8_lossy(&out.stdout);
    assert!(
        out.status.success(),
        "plyfile failed:\n{stdout}\n{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let lines: Vec<&str> = stdout.lines().collect();
    assert_eq!(lines[0], "format False <");
    assert_eq!(lines[1], format!("counts {} {}", verts.len(), tris.len()));
    assert_eq!(lines[2], "names x,y,z");
    for line in lines.iter().filter(|l| l.starts_with("v ")) {
        let w: Vec<&str> = line.split(' ').collect();
        let i: usize = w[1].parse().unwrap();
        for k in 0..3 {
            let got: f64 = w[2 + k].parse().unwrap();
            assert_eq!(got.to_bits(), verts[i][k].to_bits(), "{line}");
        }
    }
    let f0 = format!("f 0 {} {} {}", tris[0][0], tris[0][1], tris[0][2]);
    assert!(lines.contains(&f0.as_str()), "{stdout}");
    let last = tris.len() - 1;
    let fl = format!(
        "f {last} {} {} {}",
        tris[last][0], tris[last][1], tris[last][2]
    );
    assert!(lines.contains(&fl.as_str()), "{stdout}");
    assert!(lines.contains(&"comment crs EPSG:3794"), "{stdout}");
    assert!(lines.contains(&"comment hello from the test"), "{stdout}");
}

/// The LandXML output is well-formed XML in the LandXML 1.2 namespace, with points in
/// "northing easting elevation" order (Python's standard library only).
#[test]
fn landxml_is_well_formed_xml() {
    let Some(python) = ["python3", "python"].into_iter().find(|py| {
        Command::new(py)
            .args(["-c", "import xml.etree.ElementTree"])
            .output()
            .is_ok_and(|o| o.status.success())
    }) else {
        assert!(
            !data::in_ci(),
            "landxml_is_well_formed_xml: python3 is required under CI=true"
        );
        eprintln!("SKIP landxml_is_well_formed_xml: python3 not found");
        return;
    };
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("tin & <co>.xml");
    let meta = MeshMeta {
        crs: Some("PROJCS[\"D96 / TM\", GEOGCS[\"D96\"]]".into()),
        comments: vec!["a -- tricky <comment> &".into()],
    };
    let mut sink = create_mesh_sink(&path, None, &meta).unwrap();
    for p in [[10.0, 20.0, 1.0], [11.0, 20.0, 2.0], [10.0, 21.0, 3.0]] {
        sink.vertex(p).unwrap();
    }
    sink.triangle([0, 1, 2]).unwrap();
    sink.finish().unwrap();
    let script = r#"
import sys
import xml.etree.ElementTree as ET
ns = {'l': 'http://www.landxml.org/schema/LandXML-1.2'}
root = ET.parse(sys.argv[1]).getroot()
print(root.tag)
print(root.find('l:CoordinateSystem', ns).get('ogcWktCode'))
s = root.find('l:Surfaces/l:Surface', ns)
print(s.get('name'), s.find('l:Definition', ns).get('surfType'))
for p in s.findall('l:Definition/l:Pnts/l:P', ns):
    print('P', p.get('id'), p.text)
for f in s.findall('l:Definition/l:Faces/l:F', ns):
    print('F', f.text)
"#;
    let out = Command::new(python)
        .arg("-c")
        .arg(script)
        .arg(&path)
        .output()
        .unwrap();
    let stdout = String::from_utf8_lossy(&out.stdout);
    assert!(
        out.status.success(),
        "{stdout}\n{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let lines: Vec<&str> = stdout.lines().collect();
    assert_eq!(
        lines,
        [
            "{http://www.landxml.org/schema/LandXML-1.2}LandXML",
            "PROJCS[\"D96 / TM\", GEOGCS[\"D96\"]]",
            "tin & <co> TIN",
            "P 1 20 10 1",
            "P 2 20 11 2",
            "P 3 21 10 3",
            "F 1 2 3",
        ]
    );
}
