//! The block index against a plain sort, packed against wide.

use super::*;
use crate::input::las::world::Quantization;
use crate::sort::external::ExternalSorter;

/// The packed index of `pts` (points of a file of quantization `q` and header box `b`).
fn packed(
    mem: u64,
    pts: &[[f64; 3]],
    grid: TileGrid,
    q: Quantization,
    b: [[f64; 3]; 2],
    dir: &Path,
) -> BlockIndex {
    let lattice = Lattice::of(&[(q, b)]).unwrap();
    let p = Packing::new(lattice, &grid).unwrap();
    let mut s = ExternalSorter::<PackedRecord>::new(mem, dir);
    for &pt in pts {
        s.push(p.pack(grid.block_of(pt[0], pt[1]), pt).unwrap())
            .unwrap();
    }
    BlockIndex::build(
        grid,
        s.finish().unwrap(),
        Some(p),
        dir,
        DuplicatePolicy::First,
    )
    .unwrap()
}

#[test]
fn packed_and_wide_indexes_hold_the_same_points_bit_for_bit() {
    let dir = tempfile::tempdir().unwrap();
    let grid = TileGrid::new(8.0, 3).unwrap();
    let q = Quantization::new([0.01, 0.01, 0.001], [511_500.025, -122_499.965, 747.255]);
    let b = [
        [510_990.0, -123_010.0, -5.0],
        [511_050.0, -122_950.0, 2000.0],
    ];
    let mut rng = crate::geom::rng::SplitMix64::new(5);
    let pts: Vec<[f64; 3]> = (0..60_000)
        .map(|_| {
            let n = [
                rng.range(-50_900.0, -45_100.0) as i32,
                rng.range(-50_900.0, -45_100.0) as i32,
                rng.range(-752_000.0, 1_252_000.0) as i32,
            ];
            q.to_world(n)
        })
        .collect();
    // Points exactly on block edges, the box's corner and a duplicate, and the farthest outside
    // the header's box the reader lets through.
    let mut pts = pts;
    pts.push(q.to_world([-51_004, -51_004, -752_256]));
    pts.push(q.to_world([-45_001, -45_001, 1_252_746]));
    pts.extend([
        [511_000.0, -123_000.0, 1.5],
        [511_000.0, -123_000.0, 2.5],
        [510_990.0, -123_010.0, 0.0],
    ]);
    for mem in [1, 1 << 30] {
        let (w, p) = (
            index(mem, &pts, grid, dir.path()),
            packed(mem, &pts, grid, q, b, dir.path()),
        );
        assert_eq!(
            (&w.keys, &w.starts, w.occupied()),
            (&p.keys, &p.starts, p.occupied())
        );
        assert_eq!(w.hull(), p.hull());
        let (mut a, mut c) = (Vec::new(), Vec::new());
        w.read(&w.occupied(), &mut a).unwrap();
        p.read(&p.occupied(), &mut c).unwrap();
        let bits = |v: &[[f64; 3]]| v.iter().map(|p| p.map(f64::to_bits)).collect::<Vec<_>>();
        assert_eq!(bits(&a), bits(&c));
        for &k in &w.keys {
            assert_eq!(w.extent(k), p.extent(k));
            let (mut x, mut y) = (Vec::new(), Vec::new());
            w.read_block(k, &mut x).unwrap();
            p.read_block(k, &mut y).unwrap();
            assert_eq!(bits(&x), bits(&y));
        }
    }
    // A point outside the box is an error, not a wrong key.
    let lattice = Lattice::of(&[(q, b)]).unwrap();
    let pk = Packing::new(lattice, &grid).unwrap();
    let far = [520_000.0, -123_000.0, 0.0];
    assert!(pk.pack(grid.block_of(far[0], far[1]), far).is_err());
    // Boxes with more blocks than 32-bit keys count are not packed.
    let tiny = TileGrid::new(0.01, 0).unwrap();
    let cm = Quantization::new([0.01; 3], [0.0; 3]);
    let wide = Lattice::of(&[(cm, [[0.0; 3], [1e4, 1e4, 1.0]])]).unwrap();
    assert!(Packing::new(wide, &tiny).is_none());
    assert!(Packing::new(wide, &TileGrid::new(4.0, 0).unwrap()).is_some());
}

#[test]
fn spilled_and_in_memory_indexes_agree_and_keep_input_order() {
    let dir = tempfile::tempdir().unwrap();
    let grid = TileGrid::new(16.0, 2).unwrap();
    let mut pts = Vec::new();
    let mut s = 99u64;
    for i in 0..50_000 {
        s = s
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        let x = ((s >> 33) % 6400) as f64 / 100.0 - 10.0;
        let y = ((s >> 13) % 6400) as f64 / 100.0 - 20.0;
        pts.push([x, y, i as f64]);
    }
    let a = index(1, &pts, grid, dir.path());
    let b = index(1 << 30, &pts, grid, dir.path());
    assert_eq!(a.len(), 50_000);
    assert_eq!(a.occupied(), b.occupied());
    let r = BlockRect {
        x0: -2,
        y0: -3,
        x1: 5,
        y1: 4,
    };
    let (mut va, mut vb) = (Vec::new(), Vec::new());
    a.read(&r, &mut va).unwrap();
    b.read(&r, &mut vb).unwrap();
    assert_eq!(va, vb);
    assert_eq!(va.len() as u64, a.count(&r));
    let expect: Vec<[f64; 3]> = {
        let mut e: Vec<_> = pts
            .iter()
            .filter(|p| {
                let (bx, by) = grid.block_of(p[0], p[1]);
                r.contains(bx, by)
            })
            .copied()
            .collect();
        // Row-major by block, input order (z) within a block.
        e.sort_by_key(|p| {
            let (bx, by) = grid.block_of(p[0], p[1]);
            (TileGrid::key(bx, by), p[2] as u64)
        });
        e
    };
    assert_eq!(va, expect);
    // Everything, across the writer's batches: the same records, blocks and extents.
    let (mut wa, mut wb) = (Vec::new(), Vec::new());
    a.read(&a.occupied(), &mut wa).unwrap();
    b.read(&b.occupied(), &mut wb).unwrap();
    assert_eq!(wa.len(), 50_000);
    assert_eq!(wa, wb);
    assert_eq!((&a.keys, &a.starts), (&b.keys, &b.starts));
    for &k in &a.keys {
        assert_eq!(a.extent(k), b.extent(k));
    }
    assert!(a.any_in_row(0, -2, 5));
    assert!(!a.any_in_row(100, -2, 5));
    assert_eq!(std::fs::read_dir(dir.path()).unwrap().count(), 0);
}
