//! Projected box hulls: upper and lower convex chains of the 8 projected corners of a node's box.

/// Upper or lower convex chain of up to 8 projected points.
#[derive(Clone, Copy)]
pub(super) struct Chain {
    p: [(f64, f64); 8],
    n: usize,
}

impl Chain {
    pub(super) const EMPTY: Chain = Chain { p: [(0.0, 0.0); 8], n: 0 };

    /// max (upper) / min (lower) of the chain at x; x must lie in the chain's x range.
    fn eval(&self, x: f64, upper: bool) -> f64 {
        let pick = |a: f64, b: f64| if upper { a.max(b) } else { a.min(b) };
        let mut best = if upper { f64::NEG_INFINITY } else { f64::INFINITY };
        if self.n == 1 {
            best = pick(best, self.p[0].1);
        }
        for k in 1..self.n {
            let (a, b) = (self.p[k - 1], self.p[k]);
            let (l, r) = if a.0 <= b.0 { (a, b) } else { (b, a) };
            if l.0 <= x && x <= r.0 {
                if r.0 > l.0 {
                    let t = (x - l.0) / (r.0 - l.0);
                    best = pick(best, l.1 + t * (r.1 - l.1));
                } else {
                    best = pick(best, pick(l.1, r.1));
                }
            }
        }
        if !best.is_finite() {
            // x slightly outside due to round-off: fall back to the extreme of all points
            for k in 0..self.n {
                best = pick(best, self.p[k].1);
            }
        }
        best
    }
}

impl Chain {
    /// max (upper) / min (lower) of the chain over [a, b] (a <= b, inside the chain's x range):
    /// the ends and every chain vertex in between.
    pub(super) fn extreme_on(&self, a: f64, b: f64, upper: bool) -> f64 {
        let pick = |u: f64, v: f64| if upper { u.max(v) } else { u.min(v) };
        let mut best = pick(self.eval(a, upper), self.eval(b, upper));
        for k in 0..self.n {
            if a <= self.p[k].0 && self.p[k].0 <= b {
                best = pick(best, self.p[k].1);
            }
        }
        best
    }
}

fn cross2(o: (f64, f64), a: (f64, f64), b: (f64, f64)) -> f64 {
    (a.0 - o.0) * (b.1 - o.1) - (a.1 - o.1) * (b.0 - o.0)
}

/// (lower, upper) convex chains (Andrew's monotone chain).
pub(super) fn hull_chains(pts: &mut [(f64, f64); 8]) -> (Chain, Chain) {
    pts.sort_by(|a, b| a.0.total_cmp(&b.0).then(a.1.total_cmp(&b.1)));
    let mut lo = Chain::EMPTY;
    for &p in pts.iter() {
        while lo.n >= 2 && cross2(lo.p[lo.n - 2], lo.p[lo.n - 1], p) <= 0.0 {
            lo.n -= 1;
        }
        lo.p[lo.n] = p;
        lo.n += 1;
    }
    let mut up = Chain::EMPTY;
    for &p in pts.iter().rev() {
        while up.n >= 2 && cross2(up.p[up.n - 2], up.p[up.n - 1], p) <= 0.0 {
            up.n -= 1;
        }
        up.p[up.n] = p;
        up.n += 1;
    }
    (lo, up)
}
