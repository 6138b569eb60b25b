//! The public types, the quadtree over the tiles and the front-to-back traversal.

use glam::{DMat4, DVec3, DVec4};

use super::hull::{hull_chains, Chain};
use super::view::View;
use super::PIX_EPS;

const NONE: u32 = u32::MAX;

pub struct HeightGrid<'a> {
    /// row-major ny*nx, render-space z (already scaled, origin-relative), NaN = hole
    pub z: &'a [f32],
    pub nx: usize,
    pub ny: usize,
    /// render-space position of sample (0,0)
    pub x0: f64,
    pub y0: f64,
    pub dx: f64,
    pub dy: f64,
    /// tx, ty
    pub tiles: (usize, usize),
}

#[derive(Clone, Debug)]
pub struct HorizonResult {
    /// index iy*tx + ix
    pub tile_visible: Vec<bool>,
    pub nodes_visited: u32,
    pub nodes_culled: u32,
    /// one value per image column: the final horizon in pixel rows (y up from the bottom,
    /// 0..height), -inf where nothing. Rows with centre below it are hidden or empty.
    pub horizon: Vec<f32>,
    /// false when the view does not allow conservative horizon culling and everything was
    /// marked visible
    pub culling_applied: bool,
}

#[derive(Clone, Copy, Debug)]
struct Node {
    min: DVec3,
    max: DVec3,
    /// quadrant q = qx + 2*qy, qx/qy = 0 on the low-index side of the split
    children: [u32; 4],
    split_x: f64,
    split_y: f64,
    tile: u32,
}

/// Precomputed per-heightfield data (quadtree over tiles, per-node bbox, per-tile
/// boundary edges of the hole-free surface).
pub struct HorizonTree {
    valid: bool,
    z: Vec<f32>,
    pub(super) nx: usize,
    x0: f64,
    y0: f64,
    dx: f64,
    dy: f64,
    pub(super) tx: usize,
    pub(super) ty: usize,
    pub(super) bx: Vec<usize>,
    pub(super) by: Vec<usize>,
    pub(super) tile_nonempty: Vec<bool>,
    pub(super) edge_off: Vec<u32>,
    /// oriented boundary edges (global sample indices), CCW in world xy
    pub(super) edges: Vec<[u32; 2]>,
    nodes: Vec<Node>,
    root: u32,
    pub(super) flip: bool,
    scale: f64,
}

/// Projection of a node's box for the current view.
#[derive(Clone, Copy)]
pub(super) struct NodeProj {
    /// all corners have w > margin (projection is continuous)
    front: bool,
    /// all corners inside the depth range (0 <= z <= w)
    pub(super) depth_ok: bool,
    /// margin in pixels (rasterizer snapping + f32 round-off) for the box's contents
    eps: f64,
    xmin: f64,
    xmax: f64,
    lo: Chain,
    up: Chain,
}

impl HorizonTree {
    pub fn build(grid: &HeightGrid) -> Self {
        let (tx, ty) = grid.tiles;
        let (nx, ny) = (grid.nx, grid.ny);
        let valid = nx >= 2
            && ny >= 2
            && tx >= 1
            && ty >= 1
            && nx.checked_mul(ny).is_some_and(|n| grid.z.len() >= n)
            && [grid.x0, grid.y0, grid.dx, grid.dy].iter().all(|v| v.is_finite())
            && grid.dx != 0.0
            && grid.dy != 0.0;
        let ntiles = tx.saturating_mul(ty);
        let mut tree = HorizonTree {
            valid,
            z: Vec::new(),
            nx,
            x0: grid.x0,
            y0: grid.y0,
            dx: grid.dx,
            dy: grid.dy,
            tx,
            ty,
            bx: Vec::new(),
            by: Vec::new(),
            tile_nonempty: vec![false; if valid { ntiles } else { 0 }],
            edge_off: vec![0],
            edges: Vec::new(),
            nodes: Vec::new(),
            root: NONE,
            flip: grid.dx * grid.dy < 0.0,
            scale: 1.0,
        };
        if !valid {
            return tree;
        }
        tree.z = grid.z[..nx * ny].to_vec();
        tree.bx = crate::lod::tile_bounds(nx, tx);
        tree.by = crate::lod::tile_bounds(ny, ty);
        let mut tile_bb = vec![(DVec3::INFINITY, DVec3::NEG_INFINITY); ntiles];
        for iy in 0..ty {
            for ix in 0..tx {
                let t = iy * tx + ix;
                let (i0, i1) = (tree.bx[ix], tree.bx[ix + 1]);
                let (j0, j1) = (tree.by[iy], tree.by[iy + 1]);
                let (mut mn, mut mx) = (DVec3::INFINITY, DVec3::NEG_INFINITY);
                for j in j0..=j1 {
                    for i in i0..=i1 {
                        if tree.z[j * nx + i].is_finite() {
                            let p = tree.pos(i, j);
                            mn = mn.min(p);
                            mx = mx.max(p);
                        }
                    }
                }
                tile_bb[t] = (mn, mx);
                tree.tile_nonempty[t] = mn.x <= mx.x;
                let zz = &tree.z;
                let fin = |i: usize, j: usize| zz[j * nx + i].is_finite();
                let good = |i: usize, j: usize| fin(i, j) && fin(i + 1, j) && fin(i, j + 1) && fin(i + 1, j + 1);
                let edges = &mut tree.edges;
                boundary_edges((i0, i1), (j0, j1), good, tree.flip, |a, b| {
                    edges.push([(a.1 * nx + a.0) as u32, (b.1 * nx + b.0) as u32]);
                });
                tree.edge_off.push(tree.edges.len() as u32);
            }
        }
        let size = tx.max(ty).next_power_of_two();
        tree.root = tree.build_node(&tile_bb, 0, 0, size);
        if tree.root != NONE {
            let r = tree.nodes[tree.root as usize];
            tree.scale = (r.max - r.min).length() + r.min.abs().max(r.max.abs()).length() + 1.0;
        }
        tree
    }

    /// Host memory held by the tree, bytes (what the strategy's cache budgets).
    pub fn bytes(&self) -> usize {
        use std::mem::size_of;
        size_of::<Self>()
            + self.z.capacity() * size_of::<f32>()
            + (self.bx.capacity() + self.by.capacity()) * size_of::<usize>()
            + self.tile_nonempty.capacity()
            + self.edge_off.capacity() * size_of::<u32>()
            + self.edges.capacity() * size_of::<[u32; 2]>()
            + self.nodes.capacity() * size_of::<Node>()
    }

    #[inline]
    pub(super) fn pos(&self, i: usize, j: usize) -> DVec3 {
        DVec3::new(self.x0 + i as f64 * self.dx, self.y0 + j as f64 * self.dy, self.z[j * self.nx + i] as f64)
    }

    fn build_node(&mut self, bb: &[(DVec3, DVec3)], ix: usize, iy: usize, s: usize) -> u32 {
        if ix >= self.tx || iy >= self.ty {
            return NONE;
        }
        if s == 1 {
            let t = iy * self.tx + ix;
            if !self.tile_nonempty[t] {
                return NONE;
            }
            self.nodes.push(Node {
                min: bb[t].0,
                max: bb[t].1,
                children: [NONE; 4],
                split_x: 0.0,
                split_y: 0.0,
                tile: t as u32,
            });
            return (self.nodes.len() - 1) as u32;
        }
        let h = s / 2;
        let mut children = [NONE; 4];
        let (mut mn, mut mx) = (DVec3::INFINITY, DVec3::NEG_INFINITY);
        for (q, ch) in children.iter_mut().enumerate() {
            *ch = self.build_node(bb, ix + (q & 1) * h, iy + (q >> 1) * h, h);
            if *ch != NONE {
                let n = self.nodes[*ch as usize];
                mn = mn.min(n.min);
                mx = mx.max(n.max);
            }
        }
        if children.iter().all(|&c| c == NONE) {
            return NONE;
        }
        let split_x = self.x0 + self.bx[(ix + h).min(self.tx)] as f64 * self.dx;
        let split_y = self.y0 + self.by[(iy + h).min(self.ty)] as f64 * self.dy;
        self.nodes.push(Node { min: mn, max: mx, children, split_x, split_y, tile: NONE });
        (self.nodes.len() - 1) as u32
    }

    /// view_proj: column-major 4x4 (glam::DMat4) mapping render space to clip space
    /// (OpenGL/wgpu style: clip.w > 0 in front; NDC x,y in [-1,1], y up). Both perspective and
    /// orthographic work, with standard or reverse-Z depth. `eye` (render space) is only used
    /// to orient orthographic views (see the module doc).
    #[cfg(test)]
    pub fn cull(&self, view_proj: DMat4, eye: DVec3, width: u32, height: u32) -> HorizonResult {
        self.cull_in_frame(view_proj, DMat4::IDENTITY, eye, width, height)
    }

    /// [`HorizonTree::cull`] for a tree built in another frame than render space: `frame` maps the
    /// tree's coordinates (its grid's frame) to render space, and must be a rotation about the z
    /// axis plus a translation (det +1, z unchanged), so that "up" and the winding of the covered
    /// sets are those of render space. The tree then culls with `view_proj * frame`, and the bound
    /// on the GPU's f32 round-off is taken for the render-space positions the GPU actually
    /// transforms (see `View::new`). `eye` is in render space, as for `cull`.
    /// [`HorizonTree::cull`] of the tree moved by `offset` (render space) without rebuilding it:
    /// `cull_in_frame` with the translation as the frame.
    #[cfg(test)]
    pub fn cull_translated(
        &self,
        view_proj: DMat4,
        offset: DVec3,
        eye: DVec3,
        width: u32,
        height: u32,
    ) -> HorizonResult {
        self.cull_in_frame(view_proj, DMat4::from_translation(offset), eye, width, height)
    }

    pub fn cull_in_frame(&self, view_proj: DMat4, frame: DMat4, eye: DVec3, width: u32, height: u32) -> HorizonResult {
        let (w, h) = (width as usize, height as usize);
        let fallback = || HorizonResult {
            tile_visible: if self.valid {
                self.tile_nonempty.clone()
            } else {
                vec![true; self.tx.saturating_mul(self.ty)]
            },
            nodes_visited: 0,
            nodes_culled: 0,
            horizon: vec![f32::NEG_INFINITY; w],
            culling_applied: false,
        };
        if !self.valid || w == 0 || h == 0 || !view_proj.is_finite() || !frame.is_finite() {
            return fallback();
        }
        let Some(view) = View::new(view_proj, frame, eye, w, h, self.scale) else {
            return fallback();
        };
        let mut res = HorizonResult {
            tile_visible: vec![false; self.tx * self.ty],
            nodes_visited: 0,
            nodes_culled: 0,
            horizon: vec![f32::NEG_INFINITY; w],
            culling_applied: true,
        };
        if self.root == NONE {
            return res;
        }
        let mut k = vec![0u32; w];
        let mut stack: Vec<(u32, NodeProj)> = Vec::with_capacity(64);
        let mut scratch = Scratch { tile_edges: vec![(0, 0); self.tx * self.ty], ..Scratch::default() };

        res.nodes_visited += 1;
        match self.project_node(&view, self.root) {
            Some(p) => stack.push((self.root, p)),
            None => res.nodes_culled += 1,
        }
        while let Some((ni, proj)) = stack.pop() {
            if self.horizon_culled(&view, &proj, &k) {
                res.nodes_culled += 1;
                continue;
            }
            let node = self.nodes[ni as usize];
            if node.tile != NONE {
                res.tile_visible[node.tile as usize] = true;
                self.add_occluder(&view, node.tile as usize, &proj, &mut k, &stack, &mut scratch);
                continue;
            }
            let sx = view.eh.x - node.split_x * view.eh.w;
            let sy = view.eh.y - node.split_y * view.eh.w;
            let qx = usize::from(!(if self.dx > 0.0 { sx < 0.0 } else { sx > 0.0 }));
            let qy = usize::from(!(if self.dy > 0.0 { sy < 0.0 } else { sy > 0.0 }));
            let order = [qx + 2 * qy, (1 - qx) + 2 * qy, qx + 2 * (1 - qy), (1 - qx) + 2 * (1 - qy)];
            // push far to near so the nearest child is popped first
            for &q in order.iter().rev() {
                let c = node.children[q];
                if c == NONE {
                    continue;
                }
                res.nodes_visited += 1;
                match self.project_node(&view, c) {
                    Some(p) => stack.push((c, p)),
                    None => res.nodes_culled += 1,
                }
            }
        }
        for (o, &kk) in res.horizon.iter_mut().zip(&k) {
            *o = if kk == 0 { f32::NEG_INFINITY } else { kk as f32 };
        }
        res
    }

    /// None = outside the view frustum / covers no pixel centre.
    fn project_node(&self, view: &View, ni: u32) -> Option<NodeProj> {
        let n = &self.nodes[ni as usize];
        let mut clip = [DVec4::ZERO; 8];
        for (kk, c) in clip.iter_mut().enumerate() {
            let p = DVec3::new(
                if kk & 1 != 0 { n.max.x } else { n.min.x },
                if kk & 2 != 0 { n.max.y } else { n.min.y },
                if kk & 4 != 0 { n.max.z } else { n.min.z },
            );
            *c = view.clip(p);
        }
        let all = |f: fn(&DVec4) -> bool| clip.iter().all(f);
        if all(|c| c.x > c.w)
            || all(|c| c.x < -c.w)
            || all(|c| c.y > c.w)
            || all(|c| c.y < -c.w)
            || all(|c| c.z > c.w)
            || all(|c| c.z < -c.w)
            || all(|c| c.w <= 0.0)
        {
            return None;
        }
        let front = clip.iter().all(|c| c.w > view.w_margin);
        if !front {
            return Some(NodeProj {
                front: false,
                depth_ok: false,
                eps: f64::INFINITY,
                xmin: f64::NEG_INFINITY,
                xmax: f64::INFINITY,
                lo: Chain::EMPTY,
                up: Chain::EMPTY,
            });
        }
        let mut depth_ok = true;
        let mut eps: f64 = 0.0;
        for (kk, &c) in clip.iter().enumerate() {
            let p = DVec3::new(
                if kk & 1 != 0 { n.max.x } else { n.min.x },
                if kk & 2 != 0 { n.max.y } else { n.min.y },
                if kk & 4 != 0 { n.max.z } else { n.min.z },
            );
            depth_ok &= view.in_depth(p, c);
            eps = eps.max(view.err_px(p, c));
        }
        let mut pts = [(0.0, 0.0); 8];
        let (mut xmin, mut xmax, mut ymin, mut ymax) =
            (f64::INFINITY, f64::NEG_INFINITY, f64::INFINITY, f64::NEG_INFINITY);
        for (p, &c) in pts.iter_mut().zip(&clip) {
            *p = view.screen(c);
            xmin = xmin.min(p.0);
            xmax = xmax.max(p.0);
            ymin = ymin.min(p.1);
            ymax = ymax.max(p.1);
        }
        if !(xmin.is_finite() && xmax.is_finite() && ymin.is_finite() && ymax.is_finite()) {
            return Some(NodeProj {
                front: false,
                depth_ok: false,
                eps: f64::INFINITY,
                xmin: f64::NEG_INFINITY,
                xmax: f64::INFINITY,
                lo: Chain::EMPTY,
                up: Chain::EMPTY,
            });
        }
        if !eps.is_finite() {
            return Some(NodeProj {
                front: false,
                depth_ok: false,
                eps,
                xmin: f64::NEG_INFINITY,
                xmax: f64::INFINITY,
                lo: Chain::EMPTY,
                up: Chain::EMPTY,
            });
        }
        view.col_range(xmin, xmax, eps)?;
        if ymax + eps < 0.5 || ymin - eps > view.hf - 0.5 {
            return None;
        }
        let (lo, up) = hull_chains(&mut pts);
        Some(NodeProj { front, depth_ok, eps, xmin, xmax, lo, up })
    }

    fn horizon_culled(&self, view: &View, p: &NodeProj, k: &[u32]) -> bool {
        if !p.front {
            return false;
        }
        let Some((c0, c1)) = view.col_range(p.xmin, p.xmax, p.eps) else {
            return true;
        };
        for (c, &kc) in k.iter().enumerate().take(c1 + 1).skip(c0) {
            if kc as usize >= view.h {
                continue;
            }
            let xc = (c as f64 + 0.5).clamp(p.xmin, p.xmax);
            // the hull's top within eps of the column centre (its slope is unbounded near
            // the ends of the hull, so evaluate at both ends of the eps-window), grown by eps
            let (a, b) = ((xc - p.eps).max(p.xmin), (xc + p.eps).min(p.xmax));
            let top = p.up.extreme_on(a, b, true) + p.eps;
            if top < 0.5 || kc as f64 + 0.5 > top {
                continue;
            }
            let bot = p.lo.extreme_on(a, b, false) - p.eps;
            if bot > view.hf - 0.5 {
                continue;
            }
            return false;
        }
        true
    }

    /// Rows of column c below every node still on the stack (the not-yet-visited nodes).
    pub(super) fn dead_rows(view: &View, c: usize, stack: &[(u32, NodeProj)]) -> u32 {
        let xc = c as f64 + 0.5;
        let mut m = f64::INFINITY;
        for (_, p) in stack {
            if !p.front {
                return 0;
            }
            if xc < p.xmin - p.eps || xc > p.xmax + p.eps {
                continue;
            }
            let (a, b) = ((xc - p.eps).max(p.xmin), (xc + p.eps).min(p.xmax));
            let (a, b) = if a <= b { (a, b) } else { (b, a) };
            m = m.min(p.lo.extreme_on(a, b, false) - p.eps);
        }
        view.rows_below(m - PIX_EPS)
    }
}

/// Emits the oriented boundary edges of the union of good cells in the cell range
/// [i0,i1) x [j0,j1). Edges are CCW in index space (reversed when `flip`).
pub(super) fn boundary_edges(
    (i0, i1): (usize, usize),
    (j0, j1): (usize, usize),
    good: impl Fn(usize, usize) -> bool,
    flip: bool,
    mut emit: impl FnMut((usize, usize), (usize, usize)),
) {
    for j in j0..j1 {
        for i in i0..i1 {
            if !good(i, j) {
                continue;
            }
            let mut e = |a: (usize, usize), b: (usize, usize)| {
                if flip {
                    emit(b, a)
                } else {
                    emit(a, b)
                }
            };
            if j == j0 || !good(i, j - 1) {
                e((i, j), (i + 1, j));
            }
            if i + 1 == i1 || !good(i + 1, j) {
                e((i + 1, j), (i + 1, j + 1));
            }
            if j + 1 == j1 || !good(i, j + 1) {
                e((i + 1, j + 1), (i, j + 1));
            }
            if i == i0 || !good(i - 1, j) {
                e((i, j + 1), (i, j));
            }
        }
    }
}

/// The occluder pass's buffers, reused across the nodes of one cull (`super::occluder`).
#[derive(Default)]
pub(super) struct Scratch {
    /// (column, y, sign)
    pub(super) cross: Vec<(u32, f64, i8)>,
    pub(super) iv: Vec<(f64, f64)>,
    /// (column, lo, hi): rows within the margin of a boundary edge
    pub(super) unc: Vec<(u32, f64, f64)>,
    /// robustly covered intervals of one column, bottom up
    pub(super) pieces: Vec<(f64, f64)>,
    pub(super) valid: Vec<bool>,
    /// boundary edges (global sample indices) of the current occluder union
    pub(super) ue: Vec<[u32; 2]>,
    /// per tile: range in `pool` of the boundary edges it was credited with (empty = not drawn)
    pub(super) tile_edges: Vec<(u32, u32)>,
    pub(super) pool: Vec<[u32; 2]>,
}
