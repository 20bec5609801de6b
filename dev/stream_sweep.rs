//! The streaming sweep alone, without reading, sorting or writing: how much the finaliser costs on
//! top of the batch sweep. `cargo run --release --example stream_sweep -- 10M [lidar-like|uniform]`
//! prints the batch sweep's time (`sweeptin::triangulate`, sort included) and the streaming
//! sweep's (points pre-sorted and de-duplicated, events drained and dropped).

use std::time::Instant;
use sweeptin::finalise::{Event, StreamConfig, StreamPoint, StreamingSweep};

fn main() {
    let args: Vec<String> = std::env::args().collect();
    let n = sweeptin::synth::parse_count(args.get(1).map_or("1M", String::as_str))
        .expect("a count like 10M");
    let dist = args.get(2).map_or("lidar-like", String::as_str);
    let pts = match dist {
        "uniform" => sweeptin::synth::uniform(n, 1),
        _ => sweeptin::synth::lidar_like(n, 1),
    };
    let t = Instant::now();
    let tin = sweeptin::triangulate(&pts, &sweeptin::Options::default()).expect("triangulates");
    let batch = t.elapsed().as_secs_f64();
    // The batch result's vertices are distinct and in input order; sort them as the pipeline does.
    let mut sorted: Vec<(usize, [f64; 3])> = tin.vertices.iter().copied().enumerate().collect();
    sorted.sort_by(|a, b| a.1[1].total_cmp(&b.1[1]).then(a.1[0].total_cmp(&b.1[0])));
    let (mut x0, mut y0, mut x1, mut y1) = (f64::MAX, f64::MAX, f64::MIN, f64::MIN);
    for (_, p) in &sorted {
        x0 = x0.min(p[0]);
        y0 = y0.min(p[1]);
        x1 = x1.max(p[0]);
        y1 = y1.max(p[1]);
    }
    let cfg = StreamConfig {
        x_sample: sorted
            .iter()
            .step_by(sorted.len() / 4096 + 1)
            .map(|p| p.1[0])
            .collect(),
        bounds: [x0, y0, x1, y1],
        expected_points: sorted.len() as u64,
        spill: None,
        corners: false,
    };
    let sp = |(i, p): &(usize, [f64; 3])| StreamPoint {
        xy: [p[0], p[1]],
        z: p[2],
        index: *i as u64,
        constraint: sweeptin::sweep::NO_CONSTRAINT,
    };
    let t = Instant::now();
    let mut s = StreamingSweep::new(sp(&sorted[0]), &cfg);
    let mut events: Vec<Event> = Vec::with_capacity(1 << 16);
    let mut triangles = 0u64;
    for (k, p) in sorted.iter().enumerate().skip(1) {
        s.push(sp(p)).expect("sorted");
        if k % 4096 == 0 {
            s.take_events(&mut events);
            triangles += events
                .iter()
                .filter(|e| matches!(e, Event::Triangle(_)))
                .count() as u64;
            events.clear();
        }
    }
    s.finish();
    s.take_events(&mut events);
    triangles += events
        .iter()
        .filter(|e| matches!(e, Event::Triangle(_)))
        .count() as u64;
    let stream = t.elapsed().as_secs_f64();
    assert_eq!(triangles as usize, tin.triangles.len());
    println!(
        "{dist} {n}: batch (sort included) {batch:.3} s, streaming sweep {stream:.3} s \
         ({:.2} M points/s), {triangles} triangles",
        sorted.len() as f64 / stream / 1e6
    );
}
