//! The front's unit tests: the x index and its groups against walks of the node list.
use super::*;

/// A small deterministic generator (xorshift).
struct Rng(u64);
impl Rng {
    fn next(&mut self) -> u64 {
        self.0 ^= self.0 << 13;
        self.0 ^= self.0 >> 7;
        self.0 ^= self.0 << 17;
        self.0
    }
    fn unit(&mut self) -> f64 {
        (self.next() >> 11) as f64 / (1u64 << 53) as f64
    }
}

/// The bucket minima, kept lazily through inserts, removals and rebuilds (clustered x, so
/// buckets hold many nodes), give what the node walk gives, early stop included.
#[test]
fn the_indexed_long_scan_returns_what_the_node_walk_returns() {
    let mut r = Rng(0x9e37_79b9_7f4a_7c15);
    let xmap = XMap::from_sample((0..1000).map(|i| (i as f64 / 1000.0).powi(4)).collect());
    let e = EdgeId(0);
    let mut f = Front::new(VertexId(0), VertexId(1), VertexId(2), [0.5, 0.0], e, e, xmap);
    let mut live = vec![VertexId(2)];
    let (mut scanned, mut walked) = (0u64, 0u64);
    for i in 3..20_000u32 {
        let x = r.unit().powi(3);
        let n = f.locate(x);
        if f.node(n).x == x {
            continue;
        }
        if i % 3 == 0 && f.len() > 3 {
            // Remove a node (near x), often the lowest of its bucket.
            let m = if n == f.head { f.next(n) } else { n };
            if m != f.tail {
                live.retain(|&v| v != f.vertex(m));
                f.remove(m);
            }
            continue;
        }
        let y = (r.unit() * 8.0).floor();
        f.insert_after(n, VertexId(i), [x, y]);
        live.push(VertexId(i));
        if i % 7 == 0 {
            let a = r.unit().powi(3);
            let b = a + r.unit() * r.unit() * 0.5;
            // Mostly a span wholly above `enough` (the scan that ends in a finalisation).
            let enough = if i % 4 == 0 {
                (r.unit() * 9.0).floor() - 1.0
            } else {
                -1.0
            };
            let mut rest = usize::MAX;
            let walk = f.min_y_within(a, b, enough, &mut rest).unwrap();
            walked += (usize::MAX - rest) as u64;
            let fast = f.min_y_indexed(a, b, enough, &mut scanned);
            assert_eq!(walk.to_bits(), fast.to_bits(), "span {a}..{b} enough {enough}");
        }
    }
    assert_eq!(f.len(), live.len() + 2);
    // The buckets were used: fewer steps than the node walk's.
    assert!(4 * scanned < walked, "{scanned} steps against {walked}");
}

#[test]
fn locate_finds_the_segment_across_long_runs_of_empty_buckets() {
    let mut r = Rng(0x2545_f491_4f6c_dd1d);
    let xmap = XMap::from_sample((0..1000).map(|i| i as f64 / 1000.0).collect());
    let e = EdgeId(0);
    let mut f = Front::new(VertexId(0), VertexId(1), VertexId(2), [0.5, 0.0], e, e, xmap);
    for i in 3..40_000u32 {
        let x = r.unit();
        let n = f.locate(x);
        if f.node(n).x != x {
            f.insert_after(n, VertexId(i), [x, 0.0]);
        }
    }
    // Remove all but a few nodes: the index keeps its peak size, mostly empty buckets.
    let mut n = f.next(f.head);
    while n != f.tail {
        let next = f.next(n);
        if r.unit() > 0.001 {
            f.remove(n);
        }
        n = next;
    }
    let xs: Vec<f64> = std::iter::successors(Some(f.next(f.head)), |&n| Some(f.next(n)))
        .take_while(|&n| n != f.tail)
        .map(|n| f.node(n).x)
        .collect();
    for _ in 0..20_000 {
        let x = r.unit();
        let n = f.locate(x);
        let walk = xs.iter().rposition(|&v| v <= x).map_or(f64::NEG_INFINITY, |i| xs[i]);
        assert_eq!(f.node(n).x.to_bits(), walk.to_bits(), "x {x}");
    }
}
