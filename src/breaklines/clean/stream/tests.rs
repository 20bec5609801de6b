use super::{Piece, clean_streamed};
use crate::breaklines::clean::{CleanOptions, Pslg, clean};
use crate::geom::predicates::sweep_cmp;
use crate::synth::{SplitMix64, roads};

type Bits = ([u64; 3], [u64; 3], u32);

fn bits(p: &Piece) -> Bits {
    (p.lo.map(f64::to_bits), p.hi.map(f64::to_bits), p.line)
}

/// `clean()`'s graph as the streamed cleaner gives it: segments and isolated vertices in sweep
/// order of their lower end.
fn pieces(g: &Pslg) -> Vec<Bits> {
    let mut used = vec![false; g.vertices.len()];
    let mut out: Vec<Piece> = Vec::new();
    for (s, &line) in g.segments.iter().zip(&g.lines) {
        used[s[0] as usize] = true;
        used[s[1] as usize] = true;
        let (mut a, mut b) = (g.vertices[s[0] as usize], g.vertices[s[1] as usize]);
        if sweep_cmp([a[0], a[1]], [b[0], b[1]]).is_gt() {
            std::mem::swap(&mut a, &mut b);
        }
        out.push(Piece { lo: a, hi: b, line });
    }
    for (v, _) in g.vertices.iter().zip(&used).filter(|(_, u)| !**u) {
        out.push(Piece {
            lo: *v,
            hi: *v,
            line: 0,
        });
    }
    let xy = |p: [f64; 3]| [p[0], p[1]];
    out.sort_by(|a, b| {
        sweep_cmp(xy(a.lo), xy(b.lo))
            .then(sweep_cmp(xy(a.hi), xy(b.hi)))
            .then((a.lo == a.hi).cmp(&(b.lo == b.hi)))
            .then(a.line.cmp(&b.line))
    });
    out.iter().map(bits).collect()
}

/// The streamed cleaning of `lines` within `mem` bytes against `clean()`: every vertex bit for
/// bit, every segment and line, the counters and the warnings.
fn both(lines: &[Vec<[f64; 3]>], mem: u64) -> super::StreamStats {
    let dir = tempfile::tempdir().unwrap();
    let want = clean(lines, &CleanOptions::default()).unwrap();
    let mut got = clean_streamed(lines, &CleanOptions::default(), mem, dir.path()).unwrap();
    let got_pieces: Vec<Bits> = got.by_ref().map(|p| bits(&p)).collect();
    assert!(got.take_error().is_none());
    assert_eq!(got.stats, want.stats);
    assert_eq!(got.warnings, want.warnings);
    let want_pieces = pieces(&want);
    assert_eq!(got_pieces.len(), want_pieces.len());
    for (k, (g, w)) in got_pieces.iter().zip(&want_pieces).enumerate() {
        assert_eq!(g, w, "piece {k}");
    }
    got.held
}

fn with_z(lines: &[Vec<[f64; 3]>], z: impl Fn([f64; 3]) -> f64) -> Vec<Vec<[f64; 3]>> {
    lines
        .iter()
        .map(|l| l.iter().map(|&p| [p[0], p[1], z(p)]).collect())
        .collect()
}

#[test]
fn streamed_rounds_give_cleans_graph_on_road_networks() {
    for seed in 1..4 {
        let lines = roads(30_000, seed);
        let held = both(&lines, 64 << 20);
        assert!(!held.in_memory);
        assert!(held.items > 25_000, "{held:?}");
        // The sweep holds the items near one line, not the network.
        assert!(held.peak_active < held.items / 20, "{held:?}");
        assert!(held.peak_window < held.items / 20, "{held:?}");
        // Without heights (2-D lines to drape).
        both(&with_z(&lines, |_| f64::NAN), 64 << 20);
    }
    // A budget so small every round spills in many runs.
    both(&roads(20_000, 9), 1 << 20);
    // At UTM offsets (a snap distance of some 75 µm there).
    let utm: Vec<Vec<[f64; 3]>> = roads(20_000, 4)
        .iter()
        .map(|l| {
            l.iter()
                .map(|p| [447_000.0 + p[0], 5_100_000.0 + p[1], p[2]])
                .collect()
        })
        .collect();
    both(&utm, 1 << 20);
}

fn degeneracies() -> Vec<Vec<[f64; 3]>> {
    vec![
        vec![[0.0, 5.0, 1.0], [5.0, 5.0, 1.0], [10.0, 5.0, 1.0]],
        vec![[5.0, 0.0, 2.0], [5.0, 5.0, 2.0], [5.0, 10.0, 2.0]],
        vec![[7.0, 0.0, 3.0], [7.0, 10.0, 3.0]],
        vec![[10.0, 5.0, 1.0], [5.0, 5.0, 1.0]],
        vec![[2.0, 5.0, 0.5], [8.0, 5.0, 0.7], [9.0, 5.0, 4.0]],
        vec![[5.0, 8.0, 9.0], [9.0, 9.0, 9.0]],
        vec![[1.0, 1.0, 0.0], [3.0, 3.0, 0.0]],
        vec![[1.0, 3.0, 5.0], [3.0, 1.0, 5.0]],
        vec![[2.0, 0.5, 6.0], [2.0, 2.0, 6.5], [2.0, 3.5, 6.0]],
        vec![[0.5, 2.0, 7.0], [3.5, 2.0, 7.0]],
        vec![[1.0, 1.5, 8.0], [3.0, 2.5, 8.0]],
        vec![[6.0, 5.0, 3.0]],
        vec![[6.5, 6.5, 1.0]],
        vec![[4.0, 9.0, 1.0], [4.0, 9.0, 1.0], [4.0, 9.5, 1.0]],
    ]
}

#[test]
fn streamed_rounds_give_cleans_graph_on_every_degeneracy() {
    let lines = degeneracies();
    for l in [lines.clone(), with_z(&lines, |_| f64::NAN)] {
        both(&l, 1 << 20);
        // UTM-sized coordinates.
        let shifted = with_z(&l, |p| p[2]);
        let shifted: Vec<Vec<[f64; 3]>> = shifted
            .iter()
            .map(|l| {
                l.iter()
                    .map(|p| [447_000.0 + p[0] * 0.25, 5_100_000.0 + p[1] * 0.25, p[2]])
                    .collect()
            })
            .collect();
        both(&shifted, 1 << 20);
    }
    // Random near-misses on a quarter grid: crossings, T-junctions, overlaps, clusters.
    for seed in 5..7 {
        let mut rng = SplitMix64::new(seed);
        let random: Vec<Vec<[f64; 3]>> = (0..400)
            .map(|_| {
                let n = 2 + rng.below(4) as usize;
                (0..n)
                    .map(|_| {
                        let q = |r: &mut SplitMix64| (r.range(0.0, 64.0) * 4.0).round() / 4.0;
                        [q(&mut rng), q(&mut rng), rng.range(0.0, 2.0)]
                    })
                    .collect()
            })
            .collect();
        both(&random, 1 << 20);
        both(&with_z(&random, |_| f64::NAN), 1 << 20);
    }
}

#[test]
fn mixed_heights_are_cleaned_in_memory_and_streamed_out() {
    let mut lines = degeneracies();
    lines[4][0][2] = f64::NAN;
    lines[5][1][2] = f64::NAN;
    let held = both(&lines, 1 << 20);
    assert!(held.in_memory);
}

/// A road network of 200,000 segments cleaned within 4 MiB: the held items (active, waiting
/// for crossings, near the sweep line), at 128 bytes a record and twice that for their
/// containers, stay within the budget, where the whole graph (what `clean()` holds: 26 MB of
/// records alone) would not; and the graph is `clean()`'s.
#[test]
fn a_road_network_larger_than_the_budget_is_cleaned_within_it() {
    let mem = 4u64 << 20;
    let lines = roads(200_000, 3);
    let held = both(&lines, mem);
    assert!(!held.in_memory);
    assert!(held.items * 128 > 4 * mem, "{held:?}");
    let bytes = (held.peak_active + held.peak_window) * 256;
    assert!(bytes < mem / 2, "{bytes} bytes held: {held:?}");
}
