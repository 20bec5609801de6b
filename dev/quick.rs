use std::time::Instant;
fn main() {
    let args: Vec<String> = std::env::args().collect();
    let n: usize = args.get(1).map(|s| s.parse().unwrap()).unwrap_or(1_000_000);
    let dist = args.get(2).map(|s| s.as_str()).unwrap_or("uniform");
    let mut s: u64 = 0x9E3779B97F4A7C15;
    let mut r = move || {
        s ^= s << 13;
        s ^= s >> 7;
        s ^= s << 17;
        (s >> 11) as f64 / (1u64 << 53) as f64
    };
    let pts: Vec<[f64; 3]> = match dist {
        "uniform" => (0..n).map(|_| [r() * 1000.0, r() * 1000.0, 0.0]).collect(),
        "grid" => {
            let w = (n as f64).sqrt() as usize;
            (0..w * w)
                .map(|i| [(i % w) as f64, (i / w) as f64, 0.0])
                .collect()
        }
        "lidar" => {
            // scan rows: x along row with 0.5 m spacing and jitter, rows 0.5 m apart, 1 cm quantised, UTM offset
            let w = (n as f64).sqrt() as usize;
            (0..n)
                .map(|i| {
                    let row = (i / w) as f64;
                    let col = (i % w) as f64;
                    let x = 500000.0 + col * 0.5 + (r() - 0.5) * 0.1 + row * 0.01;
                    let y = 5000000.0 + row * 0.5 + (r() - 0.5) * 0.1;
                    [
                        (x * 100.0).round() / 100.0,
                        (y * 100.0).round() / 100.0,
                        0.0,
                    ]
                })
                .collect()
        }
        "cluster" => (0..n)
            .map(|i| {
                let c = (i % 50) as f64;
                let cx = (c * 37.0) % 1000.0;
                let cy = (c * 91.0) % 1000.0;
                let sc = 1.0 + (c % 7.0) * 10.0;
                [cx + (r() - 0.5) * sc, cy + (r() - 0.5) * sc, 0.0]
            })
            .collect(),
        "sclustered" => sweeptin::synth::clustered(n, 1),
        "slidar" => sweeptin::synth::lidar_like(n, 1),
        "suniform" => sweeptin::synth::uniform(n, 1),
        _ => panic!(),
    };
    if args.get(3).map(|s| s == "stream").unwrap_or(false) {
        stream(&pts);
        return;
    }
    let t0 = Instant::now();
    let prep = sweeptin::sort::memory::prepare(&pts, Default::default()).unwrap();
    let t1 = Instant::now();
    let mut sw = sweeptin::sweep::Sweep::new(prep.xy).unwrap();
    sw.run().unwrap();
    let t2 = Instant::now();
    let st = sw.stats();
    let (tris, _, _) = sw.finish();
    let t3 = Instant::now();
    println!(
        "{dist} n={n} prep {:.3}s sweep {:.3}s finish {:.3}s total {:.3}s tris {} dups {} {:?}",
        (t1 - t0).as_secs_f64(),
        (t2 - t1).as_secs_f64(),
        (t3 - t2).as_secs_f64(),
        (t3 - t0).as_secs_f64(),
        tris.len(),
        prep.duplicates,
        st
    );
    if args.get(3).map(|s| s == "check").unwrap_or(false) {
        let mut sw = sweeptin::sweep::Sweep::new(
            sweeptin::sort::memory::prepare(&pts, Default::default())
                .unwrap()
                .xy,
        )
        .unwrap();
        sw.run().unwrap();
        sw.check().unwrap();
        println!("check ok");
    }
}

#[allow(dead_code)]
pub fn stream(pts: &[[f64; 3]]) {
    use sweeptin::finalise::{Event, StreamConfig, StreamPoint, StreamingSweep};
    let t0 = Instant::now();
    let prep = sweeptin::sort::memory::prepare(pts, Default::default()).unwrap();
    let real = &prep.xy[2..];
    let (mut x0, mut y0, mut x1, mut y1) = (f64::MAX, f64::MAX, f64::MIN, f64::MIN);
    for p in real {
        x0 = x0.min(p[0]);
        x1 = x1.max(p[0]);
        y0 = y0.min(p[1]);
        y1 = y1.max(p[1]);
    }
    let cfg = StreamConfig {
        x_sample: real.iter().step_by(64).map(|p| p[0]).collect(),
        bounds: [x0, y0, x1, y1],
        expected_points: real.len() as u64,
        spill: None,
        corners: false,
    };
    let t1 = Instant::now();
    let sp = |i: usize| StreamPoint {
        xy: real[i],
        z: 0.0,
        index: i as u64,
        constraint: u32::MAX,
    };
    let mut s = StreamingSweep::new(sp(0), &cfg);
    let mut ev = Vec::new();
    let mut ntri = 0u64;
    for i in 1..real.len() {
        s.push(sp(i)).unwrap();
        if s.pending_events() > 8192 {
            s.take_events(&mut ev);
            ntri += ev
                .iter()
                .filter(|e| matches!(e, Event::Triangle(_)))
                .count() as u64;
            ev.clear();
        }
    }
    s.finish();
    s.take_events(&mut ev);
    ntri += ev
        .iter()
        .filter(|e| matches!(e, Event::Triangle(_)))
        .count() as u64;
    let t2 = Instant::now();
    println!(
        "stream: prep {:.3}s sweep {:.3}s tris {ntri} {:?} {:?}",
        (t1 - t0).as_secs_f64(),
        (t2 - t1).as_secs_f64(),
        s.stats(),
        s.stream_stats()
    );
}
