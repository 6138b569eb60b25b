//! Occluder coverage: the covered set of a drawn tile, from the boundary edges of its hole-free
//! surface (see "Occluders" in the module documentation), raises the horizon.

use super::tree::{boundary_edges, HorizonTree, NodeProj, Scratch};
use super::view::View;
use super::PIX_EPS;

impl HorizonTree {
    pub(super) fn add_occluder(
        &self,
        view: &View,
        t: usize,
        proj: &NodeProj,
        k: &mut [u32],
        stack: &[(u32, NodeProj)],
        s: &mut Scratch,
    ) {
        s.cross.clear();
        s.unc.clear();
        s.ue.clear();
        self.occluder_edges(view, t, proj, s);
        for &[a, b] in &s.ue {
            let (a, b) = (a as usize, b as usize);
            let (qa, qb) = (self.pos(a % self.nx, a / self.nx), self.pos(b % self.nx, b / self.nx));
            let (ca, cb) = (view.clip(qa), view.clip(qb));
            let (pa, pb) = (view.screen(ca), view.screen(cb));
            add_edge(pa, pb, view.w, &mut s.cross);
            add_band(pa, pb, view.err_px(qa, ca), view.err_px(qb, cb), view, &mut s.unc);
        }
        if s.cross.is_empty() {
            return;
        }
        Self::raise_columns(view, k, stack, s);
    }

    /// The boundary edges of tile `t`'s occluder into `s.ue` (the tile's own, credited to it in
    /// `s.tile_edges` / `s.pool`, joined with its drawn neighbours' and their shared sides
    /// cancelled).
    fn occluder_edges(&self, view: &View, t: usize, proj: &NodeProj, s: &mut Scratch) {
        // The occluder is the union of this tile's covered set with those of its already drawn
        // neighbours (each with the edge set it was credited with, static or per-frame): their
        // shared sides cancel, so the margin is only taken around the union's boundary. Tile seams must not get a margin: the GPU gives a
        // pixel centre near a seam to one side or the other, and both sides are drawn.
        if proj.depth_ok {
            let r = self.edge_off[t] as usize..self.edge_off[t + 1] as usize;
            s.ue.extend_from_slice(&self.edges[r]);
        } else {
            // per-frame mask: cells with 4 finite corners inside the depth range
            let (ix, iy) = (t % self.tx, t / self.tx);
            let (i0, i1) = (self.bx[ix], self.bx[ix + 1]);
            let (j0, j1) = (self.by[iy], self.by[iy + 1]);
            let lw = i1 - i0 + 1;
            s.valid.clear();
            for j in j0..=j1 {
                for i in i0..=i1 {
                    let p = self.pos(i, j);
                    s.valid.push(p.z.is_finite() && view.in_depth(p, view.clip(p)));
                }
            }
            let valid = &s.valid;
            let v = |i: usize, j: usize| valid[(j - j0) * lw + (i - i0)];
            let good = |i: usize, j: usize| v(i, j) && v(i + 1, j) && v(i, j + 1) && v(i + 1, j + 1);
            let (nx, ue) = (self.nx, &mut s.ue);
            boundary_edges((i0, i1), (j0, j1), good, self.flip, |a, b| {
                ue.push([(a.1 * nx + a.0) as u32, (b.1 * nx + b.0) as u32]);
            });
        }
        let own = s.ue.len();
        s.tile_edges[t] = (s.pool.len() as u32, (s.pool.len() + own) as u32);
        s.pool.extend_from_slice(&s.ue);
        let (ix, iy) = ((t % self.tx) as isize, (t / self.tx) as isize);
        for (ddx, ddy) in [(-1, -1), (0, -1), (1, -1), (-1, 0), (1, 0), (-1, 1), (0, 1), (1, 1)] {
            let (jx, jy) = (ix + ddx, iy + ddy);
            if jx < 0 || jy < 0 || jx >= self.tx as isize || jy >= self.ty as isize {
                continue;
            }
            let u = jy as usize * self.tx + jx as usize;
            let (a, b) = s.tile_edges[u];
            if a < b {
                s.ue.extend_from_slice(&s.pool[a as usize..b as usize]);
            }
        }
        if s.ue.len() > own {
            // cancel opposite pairs (a shared side appears once in each tile, reversed)
            s.ue.sort_unstable_by_key(|e| (e[0].min(e[1]), e[0].max(e[1])));
            let mut out = 0;
            let mut i = 0;
            while i < s.ue.len() {
                if i + 1 < s.ue.len() && s.ue[i][0] == s.ue[i + 1][1] && s.ue[i][1] == s.ue[i + 1][0] {
                    i += 2;
                    continue;
                }
                s.ue[out] = s.ue[i];
                out += 1;
                i += 1;
            }
            s.ue.truncate(out);
        }
    }

    /// Raises the horizon `k` of every column the occluder's crossings (`s.cross`) cover, less
    /// the rows within the margin of its boundary edges (`s.unc`).
    fn raise_columns(view: &View, k: &mut [u32], stack: &[(u32, NodeProj)], s: &mut Scratch) {
        s.cross.sort_unstable_by(|a, b| a.0.cmp(&b.0).then(b.1.total_cmp(&a.1)));
        s.unc.sort_unstable_by(|a, b| a.0.cmp(&b.0).then(a.1.total_cmp(&b.1)));
        let mut ui = 0;
        let mut idx = 0;
        let n = s.cross.len();
        while idx < n {
            let c = s.cross[idx].0 as usize;
            let mut end = idx;
            while end < n && s.cross[end].0 as usize == c {
                end += 1;
            }
            // walk from the top down; winding above the first crossing is 0
            s.iv.clear();
            let mut wnd = 0i32;
            let mut prev = f64::INFINITY;
            for e in &s.cross[idx..end] {
                if wnd >= 1 {
                    s.iv.push((e.1, prev));
                }
                wnd += e.2 as i32;
                prev = e.1;
            }
            idx = end;
            // remove the rows within the margin of any boundary edge: what remains is covered
            // for every position of the edges the GPU may rasterize
            while ui < s.unc.len() && (s.unc[ui].0 as usize) < c {
                ui += 1;
            }
            let mut ue = ui;
            while ue < s.unc.len() && s.unc[ue].0 as usize == c {
                ue += 1;
            }
            s.pieces.clear();
            for &(lo, hi) in s.iv.iter().rev() {
                let mut cur = lo;
                for &(_, ulo, uhi) in &s.unc[ui..ue] {
                    if uhi <= cur || ulo >= hi {
                        continue;
                    }
                    if ulo > cur {
                        s.pieces.push((cur, ulo));
                    }
                    cur = cur.max(uhi);
                }
                if cur < hi {
                    s.pieces.push((cur, hi));
                }
            }
            ui = ue;
            let mut kk = k[c];
            let mut dead_done = false;
            'outer: for &(lo, hi) in s.pieces.iter() {
                loop {
                    if kk as usize >= view.h {
                        break 'outer;
                    }
                    if lo + PIX_EPS < kk as f64 + 0.5 {
                        kk = kk.max(view.rows_below(hi - PIX_EPS));
                        break;
                    } else if !dead_done {
                        dead_done = true;
                        kk = kk.max(Self::dead_rows(view, c, stack));
                    } else {
                        break 'outer;
                    }
                }
            }
            k[c] = kk;
        }
    }
}

/// For each pixel column whose centre may be within the margin of the projected edge a-b: the
/// interval of y on the centre line within the margin of the edge. The margin varies linearly
/// along the edge from `ea` (at a) to `eb` (at b): a point of the segment moves by at most the
/// convex combination of its endpoints' moves, which matters for edges with one end near the eye
/// (huge margin) and the other far away. Per column, with E the largest margin over the part of
/// the edge inside the window [xc - E, xc + E] (E = e(xc) / (1 - |de/dx|)), the interval is the
/// y range of that part grown by E (a superset of the true band).
#[inline]
fn add_band(a: (f64, f64), b: (f64, f64), ea: f64, eb: f64, view: &View, out: &mut Vec<(u32, f64, f64)>) {
    if !(a.0.is_finite() && a.1.is_finite() && b.0.is_finite() && b.1.is_finite()) {
        return;
    }
    if !(ea.is_finite() && eb.is_finite()) {
        return; // cannot happen for in-range points; the caller only credits finite ones
    }
    let ((l, el), (r, er)) = if a.0 <= b.0 { ((a, ea), (b, eb)) } else { ((b, eb), (a, ea)) };
    let emax = el.max(er);
    let Some((c0, c1)) = view.col_range(l.0, r.0, emax) else {
        return;
    };
    let dx = r.0 - l.0;
    let slope = if dx > 0.0 { (er - el).abs() / dx } else { f64::INFINITY };
    let at = |x: f64| {
        if dx > 0.0 {
            let t = ((x - l.0) / dx).clamp(0.0, 1.0);
            (l.1 + t * (r.1 - l.1), el + t * (er - el))
        } else {
            (l.1, el)
        }
    };
    for c in c0..=c1 {
        let xc = c as f64 + 0.5;
        let e = if slope < 0.5 { (at(xc).1 / (1.0 - slope)).min(emax) } else { emax };
        let (x0, x1) = ((xc - e).max(l.0), (xc + e).min(r.0));
        if x0 > x1 {
            continue;
        }
        let (y0, y1) = if dx > 0.0 { (at(x0).0, at(x1).0) } else { (l.1, r.1) };
        out.push((c as u32, y0.min(y1) - e, y0.max(y1) + e));
    }
}

/// Crossings of the projected edge a->b with the pixel-centre lines x = c + 0.5
/// (half-open rule). Sign: +1 when the edge runs right-to-left, so that the winding number of a
/// point is the sum of the signs of the crossings above it.
#[inline]
fn add_edge(a: (f64, f64), b: (f64, f64), w: usize, out: &mut Vec<(u32, f64, i8)>) {
    if a.0 == b.0 || !(a.0.is_finite() && b.0.is_finite()) {
        return;
    }
    let (l, r, sign) = if a.0 < b.0 { (a, b, -1i8) } else { (b, a, 1i8) };
    // columns with l.x <= c + 0.5 < r.x
    let c0 = (l.0 - 0.5).ceil().max(0.0);
    let c1 = ((r.0 - 0.5).ceil() - 1.0).min(w as f64 - 1.0);
    if c0 > c1 {
        return;
    }
    let inv = 1.0 / (r.0 - l.0);
    for c in c0 as usize..=c1 as usize {
        let t = (c as f64 + 0.5 - l.0) * inv;
        out.push((c as u32, l.1 + t * (r.1 - l.1), sign));
    }
}
