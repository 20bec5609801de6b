//! Vertical errors of a TIN against lidar points, measured independently of `sweeptin thin` and
//! `simplify` (for `scripts/bench-thin.sh`): every point is looked up in a uniform grid of the
//! TIN's triangles and interpolated by barycentric weights in floating point; a point in several
//! triangles (on an edge) takes the smallest error, a point in none is counted as uncovered.
//! Prints one JSON object: points, uncovered, max and RMS error over all points and over the
//! distinct positions (the first point of each), and how many exceed a tolerance.
//!
//! `cargo run --release --example tin_errors -- MESH.ply TOL FILE.laz [CLASS]`

fn main() -> anyhow::Result<()> {
    let args: Vec<String> = std::env::args().collect();
    anyhow::ensure!(
        args.len() == 4 || args.len() == 5,
        "usage: tin_errors MESH.ply TOL POINTS.laz [CLASS]"
    );
    let (vertices, triangles) = sweeptin::input::ply::read_ply(&args[1])?;
    let tol: f64 = args[2].parse()?;
    let filter = sweeptin::input::las::Filter {
        classes: args
            .get(4)
            .map(|c| c.parse().map(|c| vec![c]))
            .transpose()?,
        ..Default::default()
    };
    let mut r = sweeptin::input::las::LidarReader::open(&[&args[3]], &filter)?;
    let pts: Vec<[f64; 3]> = r.read_all()?.iter().map(|p| [p.x, p.y, p.z]).collect();

    // Uniform grid over the triangles' boxes, about 2 triangles per cell.
    let (mut lo, mut hi) = ([f64::INFINITY; 2], [f64::NEG_INFINITY; 2]);
    for v in &vertices {
        for k in 0..2 {
            lo[k] = lo[k].min(v[k]);
            hi[k] = hi[k].max(v[k]);
        }
    }
    let n = ((triangles.len() as f64 / 2.0).sqrt().ceil() as usize).max(1);
    let size = [(hi[0] - lo[0]) / n as f64, (hi[1] - lo[1]) / n as f64];
    let cell = |x: f64, k: usize| (((x - lo[k]) / size[k]).floor().max(0.0) as usize).min(n - 1);
    let mut cells: Vec<Vec<u32>> = vec![Vec::new(); n * n];
    for (t, tri) in triangles.iter().enumerate() {
        let p = tri.map(|i| vertices[i as usize]);
        let (x0, x1) = (
            p[0][0].min(p[1][0]).min(p[2][0]),
            p[0][0].max(p[1][0]).max(p[2][0]),
        );
        let (y0, y1) = (
            p[0][1].min(p[1][1]).min(p[2][1]),
            p[0][1].max(p[1][1]).max(p[2][1]),
        );
        for cy in cell(y0, 1)..=cell(y1, 1) {
            for cx in cell(x0, 0)..=cell(x1, 0) {
                cells[cy * n + cx].push(t as u32);
            }
        }
    }
    let error_at = |p: [f64; 3]| -> Option<f64> {
        let mut best: Option<f64> = None;
        for &t in &cells[cell(p[1], 1) * n + cell(p[0], 0)] {
            let [a, b, c] = triangles[t as usize].map(|i| vertices[i as usize]);
            let det = (b[0] - a[0]) * (c[1] - a[1]) - (b[1] - a[1]) * (c[0] - a[0]);
            let wb = ((p[0] - a[0]) * (c[1] - a[1]) - (p[1] - a[1]) * (c[0] - a[0])) / det;
            let wc = ((b[0] - a[0]) * (p[1] - a[1]) - (b[1] - a[1]) * (p[0] - a[0])) / det;
            let wa = 1.0 - wb - wc;
            let eps = -1e-9;
            if wa >= eps && wb >= eps && wc >= eps {
                let z = wa * a[2] + wb * b[2] + wc * c[2];
                let e = (p[2] - z).abs();
                best = Some(best.map_or(e, |b: f64| b.min(e)));
            }
        }
        best
    };
    let mut order: Vec<u32> = (0..pts.len() as u32).collect();
    order.sort_by(|&a, &b| {
        let (p, q) = (pts[a as usize], pts[b as usize]);
        p[1].total_cmp(&q[1])
            .then(p[0].total_cmp(&q[0]))
            .then(a.cmp(&b))
    });
    #[derive(Default)]
    struct Acc {
        n: u64,
        uncovered: u64,
        max: f64,
        sum2: f64,
        beyond: u64,
    }
    let (mut all, mut distinct) = (Acc::default(), Acc::default());
    let mut prev: Option<[f64; 2]> = None;
    for &i in &order {
        let p = pts[i as usize];
        let first = prev != Some([p[0], p[1]]);
        prev = Some([p[0], p[1]]);
        let e = error_at(p);
        for (acc, on) in [(&mut all, true), (&mut distinct, first)] {
            if !on {
                continue;
            }
            acc.n += 1;
            match e {
                None => acc.uncovered += 1,
                Some(e) => {
                    acc.max = acc.max.max(e);
                    acc.sum2 += e * e;
                    acc.beyond += u64::from(e > tol * (1.0 + 1e-9));
                }
            }
        }
    }
    let json = |a: &Acc| {
        format!(
            "{{\"points\":{},\"uncovered\":{},\"max_error\":{},\"rms_error\":{},\"beyond_tol\":{}}}",
            a.n,
            a.uncovered,
            a.max,
            (a.sum2 / (a.n - a.uncovered).max(1) as f64).sqrt(),
            a.beyond
        )
    };
    println!(
        "{{\"vertices\":{},\"triangles\":{},\"all\":{},\"distinct\":{}}}",
        vertices.len(),
        triangles.len(),
        json(&all),
        json(&distinct)
    );
    Ok(())
}
