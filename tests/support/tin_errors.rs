//! An independent check of a TIN's vertical errors (`sweeptin thin`'s tests): no code of the
//! crate, floating-point barycentric weights.

/// Largest vertical distance of `pts` from the TIN (the smallest over the triangles that hold a
/// point, for points on edges), and how many points no triangle holds. Independent of the
/// thinning: a uniform grid of triangle boxes, barycentric weights in floating point.
pub fn tin_errors(vertices: &[[f64; 3]], triangles: &[[u32; 3]], pts: &[[f64; 3]]) -> (f64, usize) {
    let (mut lo, mut hi) = ([f64::INFINITY; 2], [f64::NEG_INFINITY; 2]);
    for v in vertices {
        for k in 0..2 {
            lo[k] = lo[k].min(v[k]);
            hi[k] = hi[k].max(v[k]);
        }
    }
    let n = ((triangles.len() as f64).sqrt().ceil() as usize).max(1);
    let size = [0, 1].map(|k| (hi[k] - lo[k]) / n as f64);
    let cell = |x: f64, k: usize| (((x - lo[k]) / size[k]).floor().max(0.0) as usize).min(n - 1);
    let mut cells: Vec<Vec<usize>> = vec![Vec::new(); n * n];
    for (t, tri) in triangles.iter().enumerate() {
        let p = tri.map(|i| vertices[i as usize]);
        let x = p.map(|q| q[0]);
        let y = p.map(|q| q[1]);
        let (x0, x1) = (x[0].min(x[1]).min(x[2]), x[0].max(x[1]).max(x[2]));
        let (y0, y1) = (y[0].min(y[1]).min(y[2]), y[0].max(y[1]).max(y[2]));
        for cy in cell(y0, 1)..=cell(y1, 1) {
            for cx in cell(x0, 0)..=cell(x1, 0) {
                cells[cy * n + cx].push(t);
            }
        }
    }
    let (mut max, mut uncovered) = (0.0f64, 0);
    for p in pts {
        let mut best: Option<f64> = None;
        for &t in &cells[cell(p[1], 1) * n + cell(p[0], 0)] {
            let [a, b, c] = triangles[t].map(|i| vertices[i as usize]);
            let det = (b[0] - a[0]) * (c[1] - a[1]) - (b[1] - a[1]) * (c[0] - a[0]);
            let wb = ((p[0] - a[0]) * (c[1] - a[1]) - (p[1] - a[1]) * (c[0] - a[0])) / det;
            let wc = ((b[0] - a[0]) * (p[1] - a[1]) - (b[1] - a[1]) * (p[0] - a[0])) / det;
            let wa = 1.0 - wb - wc;
            if wa >= -1e-9 && wb >= -1e-9 && wc >= -1e-9 {
                let e = (p[2] - (wa * a[2] + wb * b[2] + wc * c[2])).abs();
                best = Some(best.map_or(e, |b: f64| b.min(e)));
            }
        }
        match best {
            Some(e) => max = max.max(e),
            None => uncovered += 1,
        }
    }
    (max, uncovered)
}
