//! Conservative horizon occlusion culling for tiled height fields.
//!
//! Based on the idea of Yalım, "Horizon occlusion culling for real-time rendering of
//! hierarchical terrains": traverse a quadtree over the tiles front to back, keep one
//! horizon value per image column, cull a node whose projected bounding box lies below the
//! horizon in every column it touches, and raise the horizon with the occluders of every
//! tile that is drawn.
//!
//! # What the horizon means
//!
//! `K[c]` (an integer row count, exported as `horizon[c] = K[c]`, or `-inf` when `K[c] == 0`)
//! says: in pixel column `c`, no pixel row `r < K[c]` (rows counted from the bottom, pixel
//! centres at `r + 0.5`) can show a surface point of any node that has not been visited yet.
//! Either the pixel is covered by an already drawn triangle that lies nearer along the pixel's
//! ray than every not-yet-visited node, or no not-yet-visited node's bounding box projects onto
//! that pixel at all ("dead" rows below the remaining nodes, see `dead_rows`).
//!
//! # Occluders (deviation from the paper, on purpose)
//!
//! The paper raises the horizon with segments lying below the tile edges and justifies it with
//! "terrain fills the screen from the bottom up". That argument is not sound with holes (NaN),
//! at the borders of the data, for a pitched camera (vertical lines converge) or near the
//! near plane. Instead, every drawn tile contributes the exact *covered set* of its rendered
//! surface, which is computed from the boundary edges only:
//!
//! * A "good" cell is a grid cell whose 4 corners are finite, so both of its triangles are
//!   drawn whatever the diagonal. The union `P` of the good cells of a tile is a continuous
//!   piecewise-linear surface (disk(s) with holes allowed). Its boundary is the set of cell
//!   sides with a good cell on exactly one side (or on the tile border), oriented
//!   counter-clockwise in world xy. Those edges are precomputed per tile at `build` time
//!   (finest samples, so interior rows/columns of the tile are implicitly used: a tile with
//!   holes still occludes with all of its hole-free part, not just with its border).
//! * Degree theory: if all of `P` lies strictly in front of the eye (and inside the depth
//!   range), the winding number of the projected boundary around a screen point `p` equals
//!   the signed number of points of `P` projecting to `p` (+1 for an up-facing surface seen
//!   from above). Winding `>= 1` therefore proves that the ray through `p` hits an up-facing
//!   (front-facing even if the renderer culls back faces with "up = front") drawn triangle of
//!   this tile inside the clip volume. Per column the winding is evaluated exactly at the
//!   pixel-centre x (half-open crossing rule), so partially covered columns are handled exactly.
//! * Margins for the GPU: a rasterizer snaps vertices to its sub-pixel grid (1/256 px on
//!   lavapipe, >= 1/16 px on any Vulkan device) and computes clip coordinates from f32 positions
//!   with an f32 matrix. A pixel centre is credited only if it is at least `eps` pixels from every
//!   edge of the occluder's boundary (`RASTER_EPS` plus a per-vertex bound of the f32 round-off,
//!   which grows near the eye and with the size of the coordinates; see `View::err_px`; along an
//!   edge it is interpolated between the endpoints' margins, see `add_band`), and occludee boxes
//!   are grown by the largest margin of their corners. Seen through the real renderer, crediting a pixel
//!   0.001 px inside a tile's border edge culled the neighbour tile that the GPU actually gave the
//!   pixel to. Tile seams get no margin: the occluder of a drawn tile is the union of its covered
//!   set with those of its already drawn 8 neighbours (shared sides cancel), and the GPU's shared
//!   vertices make the seam watertight, so a pixel near a seam goes to one of two drawn tiles.
//!   "In the depth range" also keeps an f32 margin, so the GPU never clips a credited cell.
//! * Front-to-back order: children are visited as (eye quadrant, the two adjacent quadrants,
//!   opposite quadrant), decided by which side of the node's two vertical split planes the
//!   centre of projection lies on. For two nodes A visited before B there is always a split
//!   plane with A (and the eye) on one closed side and B on the other, so along every ray every
//!   point of A comes no later than every point of B. Hence a covering point found in A is
//!   nearer than anything in B (ties only exactly on the shared plane, measure zero).
//! * A covered interval `(lo, hi)` in a column only raises `K[c]` if it is contiguous with
//!   the rows already known hidden (`lo` below the centre of row `K[c]`). If it is not, the
//!   dead rows below the lower envelope of all nodes still on the traversal stack (= exactly
//!   the not-yet-visited nodes) are added first, which makes culling work when the camera is
//!   outside the data and the bottom of the screen shows nothing.
//! * Tiles whose bounding box reaches outside the depth range (e.g. the tile under the eye)
//!   use a per-frame mask instead: a cell is good only if its 4 corners are finite AND
//!   inside the depth range (`w > margin`, `0 <= z_clip <= w`); this is evaluated on the fly
//!   for these few tiles only.
//!
//! # Culling test
//!
//! A node is frustum-culled when all 8 box corners are outside one clip plane
//! (`x>w`, `x<-w`, `y>w`, `y<-w`, `z>w`, `z<-w`, `w<=0`; valid for GL and wgpu depth ranges)
//! or when its projected hull contains no pixel centre. Otherwise, if any corner has
//! `w <= margin` the node is kept. Else the projected box hull is evaluated per pixel column
//! (exact upper/lower convex hull of the 8 projected corners at the pixel-centre x) and the
//! node is culled iff every row centre the hull can reach in every column it spans is `< K[c]`.
//! Both kinds of culls are counted in `nodes_culled`.
//!
//! # Depth conventions
//!
//! Standard depth and reverse-Z (the renderer: infinite-far reverse-Z perspective, reverse-Z
//! orthographic, `Greater` test) both work: the clip tests only use `0 <= z <= w` (the wgpu /
//! Vulkan / D3D range, either orientation) and `w > 0`. Front-to-back order comes from the
//! centre of projection (perspective) or the projection direction (orthographic). For
//! orthographic views the direction's sign cannot be read from the matrix (depth grows forward
//! with standard depth, backward with reverse-Z), so `eye` decides: its depth is <= 0 with
//! standard depth and >= 1 with reverse-Z. (Before this rule, reverse-Z orthographic views were
//! traversed back to front and culled visible tiles.)
//!
//! # Validity rule (when `culling_applied == false`)
//!
//! The argument above needs no "eye above terrain", no "no roll" and no particular pitch: it
//! only needs a projective `view_proj` with a centre of projection (perspective) or a
//! projection direction (orthographic), `w > 0` in front, depth monotone along rays (true for
//! any standard or reverse-Z projection), pixel-centre sampling without MSAA, nearest-wins
//! depth test, and full-resolution triangles (two per cell, dropped iff a corner is NaN).
//! Eye below the terrain / looking at the underside: the winding there is negative, so no
//! occluder is credited and the result is conservative (little or no culling).
//! Culling is *disabled* (all non-empty tiles visible, `culling_applied = false`) when:
//! * the grid is invalid (nx<2, ny<2, no tiles, z too short, non-finite or zero spacing),
//!   or width/height is 0 (then every tile, even empty ones, is reported visible for an
//!   invalid grid);
//! * `view_proj` is not finite or degenerate (no centre/direction of projection, or the
//!   forward direction cannot be determined);
//! * the view direction is within 30 degrees of vertical (`|forward.z| > sin 60°`): there a
//!   bottom-up horizon cannot rise (the nadir projects into the screen), so the traversal
//!   would cost time for nothing. This is a usefulness rule, not a correctness one.
//!
//! The centre of projection is derived from `view_proj` itself, so the ordering can never
//! disagree with what is rendered; `eye` (render space, consistent with `view_proj`) is only used
//! for the sign of an orthographic view direction (see "Depth conventions").
//! Not covered: LOD rendering (coarser meshes than the finest samples) - the covered set is
//! computed for the full-resolution surface; MSAA (sub-pixel samples other than the centre).

use glam::{DMat4, DVec3, DVec4};

const NONE: u32 = u32::MAX;
/// Safety margin in pixels against floating-point round-off (of this module's f64 arithmetic).
const PIX_EPS: f64 = 1e-4;
/// Rasterizer margin in pixels: a GPU snaps vertex positions to its sub-pixel grid before testing
/// pixel centres (lavapipe/llvmpipe and desktop GPUs: 8 bits = 1/256 px; Vulkan's minimum is
/// 4 bits = 1/16 px, i.e. a vertex moves by at most 1/32 px per axis). Coverage is credited only at
/// pixel centres at least this far (plus the f32 bound below) from every occluder boundary edge,
/// and occludee boxes are grown by it.
const RASTER_EPS: f64 = 1.0 / 16.0;
/// Bound on the relative f32 round-off of the GPU's clip coordinates (positions rounded to f32,
/// f32 matrix, a 4-term dot product): a few units of 2^-24 of the sum of absolute terms, with margin.
const F32_REL: f64 = 8.0 / 16_777_216.0;
/// Culling is disabled when |forward.z| exceeds this (view within 30° of vertical).
const STEEP_SIN: f64 = 0.866_025_403_784_438_6;

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
    nx: usize,
    x0: f64,
    y0: f64,
    dx: f64,
    dy: f64,
    tx: usize,
    ty: usize,
    bx: Vec<usize>,
    by: Vec<usize>,
    tile_nonempty: Vec<bool>,
    edge_off: Vec<u32>,
    /// oriented boundary edges (global sample indices), CCW in world xy
    edges: Vec<[u32; 2]>,
    nodes: Vec<Node>,
    root: u32,
    flip: bool,
    scale: f64,
}

/// Emits the oriented boundary edges of the union of good cells in the cell range
/// [i0,i1) x [j0,j1). Edges are CCW in index space (reversed when `flip`).
fn boundary_edges(
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

/// Upper or lower convex chain of up to 8 projected points.
#[derive(Clone, Copy)]
struct Chain {
    p: [(f64, f64); 8],
    n: usize,
}

impl Chain {
    const EMPTY: Chain = Chain { p: [(0.0, 0.0); 8], n: 0 };

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
    fn extreme_on(&self, a: f64, b: f64, upper: bool) -> f64 {
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
fn hull_chains(pts: &mut [(f64, f64); 8]) -> (Chain, Chain) {
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

/// Projection of a node's box for the current view.
#[derive(Clone, Copy)]
struct NodeProj {
    /// all corners have w > margin (projection is continuous)
    front: bool,
    /// all corners inside the depth range (0 <= z <= w)
    depth_ok: bool,
    /// margin in pixels (rasterizer snapping + f32 round-off) for the box's contents
    eps: f64,
    xmin: f64,
    xmax: f64,
    lo: Chain,
    up: Chain,
}

struct View {
    m: DMat4,
    /// |rows| of `m` (x, y, z, w), for the f32 error bound of clip coordinates
    ra: [DVec4; 4],
    /// homogeneous centre of projection (w = 1 perspective, w = 0 orthographic: -view dir)
    eh: DVec4,
    w_margin: f64,
    wf: f64,
    hf: f64,
    w: usize,
    h: usize,
}

impl View {
    fn new(m: DMat4, eye: DVec3, w: usize, h: usize, scale: f64) -> Option<View> {
        let r0 = m.row(0);
        let r1 = m.row(1);
        let r2 = m.row(2);
        let r3 = m.row(3);
        let drop = |v: DVec4, k: usize| match k {
            0 => DVec3::new(v.y, v.z, v.w),
            1 => DVec3::new(v.x, v.z, v.w),
            2 => DVec3::new(v.x, v.y, v.w),
            _ => DVec3::new(v.x, v.y, v.z),
        };
        let det3 = |a: DVec3, b: DVec3, c: DVec3| a.dot(b.cross(c));
        let n = DVec4::new(
            det3(drop(r0, 0), drop(r1, 0), drop(r3, 0)),
            -det3(drop(r0, 1), drop(r1, 1), drop(r3, 1)),
            det3(drop(r0, 2), drop(r1, 2), drop(r3, 2)),
            -det3(drop(r0, 3), drop(r1, 3), drop(r3, 3)),
        );
        let n3 = n.truncate();
        if !n.is_finite() || n3.length() == 0.0 && n.w == 0.0 {
            return None;
        }
        // forward direction: rays through NDC (0,0); orient so that w (or depth) grows
        let mut f = r0.truncate().cross(r1.truncate());
        let fl = f.length();
        if fl <= 0.0 || !fl.is_finite() {
            return None;
        }
        let s3 = r3.truncate().dot(f);
        let s2 = r2.truncate().dot(f);
        let tiny = 1e-12 * fl;
        if s3.abs() > tiny * r3.truncate().length().max(1e-300) {
            // perspective: w (the distance along the view axis) grows forward
            f *= s3.signum();
        } else if s2.abs() > tiny * r2.truncate().length().max(1e-300) {
            // orthographic: depth is linear along f, but whether it grows forward (standard depth,
            // near -> 0, far -> 1) or backward (reverse-Z, near -> 1, far -> 0) cannot be read
            // from the matrix. The eye decides: it lies at or before the near plane, so its depth
            // is <= 0 for standard depth and >= 1 for reverse-Z.
            let ce = m * eye.extend(1.0);
            if !ce.is_finite() || ce.w <= 0.0 {
                return None;
            }
            let reverse = ce.z / ce.w >= 0.5;
            f *= if reverse { -s2.signum() } else { s2.signum() };
        } else {
            return None;
        }
        let f = f / fl;
        if f.z.abs() > STEEP_SIN {
            return None;
        }
        let eh = if n.w != 0.0 && n3.length() / n.w.abs() <= 1e9 * scale {
            (n3 / n.w).extend(1.0)
        } else {
            (-f).extend(0.0)
        };
        if !eh.is_finite() {
            return None;
        }
        let w_margin = (1e-9 * (r3.truncate().length() * scale + r3.w.abs())).max(1e-300);
        Some(View { m, ra: [r0.abs(), r1.abs(), r2.abs(), r3.abs()], eh, w_margin, wf: w as f64, hf: h as f64, w, h })
    }

    #[inline]
    fn clip(&self, p: DVec3) -> DVec4 {
        self.m * p.extend(1.0)
    }

    #[inline]
    fn screen(&self, c: DVec4) -> (f64, f64) {
        ((c.x / c.w + 1.0) * 0.5 * self.wf, (c.y / c.w + 1.0) * 0.5 * self.hf)
    }

    /// Bound on the f32 round-off of clip coordinate `row` of render-space point `p` on the GPU.
    #[inline]
    fn f32_err(&self, row: usize, p: DVec3) -> f64 {
        F32_REL * (self.ra[row].truncate().dot(p.abs()) + self.ra[row].w)
    }

    /// Pixels by which the GPU's projection of `p` (clip `c`, w > 0) may differ from ours:
    /// sub-pixel snapping plus the f32 bound. Infinite when w is not safely positive.
    #[inline]
    fn err_px(&self, p: DVec3, c: DVec4) -> f64 {
        let ew = self.f32_err(3, p);
        if !(c.w > ew + self.w_margin) {
            return f64::INFINITY;
        }
        let ex = (self.f32_err(0, p) + (c.x / c.w).abs() * ew) / (c.w - ew);
        let ey = (self.f32_err(1, p) + (c.y / c.w).abs() * ew) / (c.w - ew);
        RASTER_EPS + PIX_EPS + (0.5 * self.wf * ex).max(0.5 * self.hf * ey)
    }

    /// Inside the depth range `0 <= z <= w` (wgpu/Vulkan/D3D; holds for standard and reverse-Z)
    /// with a margin for the GPU's f32 round-off, so the GPU does not clip it.
    #[inline]
    fn in_depth(&self, p: DVec3, c: DVec4) -> bool {
        let (ez, ew) = (self.f32_err(2, p), self.f32_err(3, p));
        c.w > self.w_margin + ew && c.z >= ez && c.z <= c.w - ez - ew
    }

    /// Number of rows whose centre is < y (clamped to 0..=h).
    #[inline]
    fn rows_below(&self, y: f64) -> u32 {
        let v = (y - 0.5).ceil();
        if v <= 0.0 {
            0
        } else if v >= self.hf {
            self.h as u32
        } else if v.is_nan() {
            0
        } else {
            v as u32
        }
    }

    /// Columns whose centre lies in [xmin - eps, xmax + eps], clipped to the screen.
    fn col_range(&self, xmin: f64, xmax: f64, eps: f64) -> Option<(usize, usize)> {
        let c0 = (xmin - eps - 0.5).ceil().max(0.0);
        let c1 = (xmax + eps - 0.5).floor().min(self.wf - 1.0);
        if c0 > c1 || c0.is_nan() || c1.is_nan() {
            None
        } else {
            Some((c0 as usize, c1 as usize))
        }
    }
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

    #[inline]
    fn pos(&self, i: usize, j: usize) -> DVec3 {
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
    pub fn cull(&self, view_proj: DMat4, eye: DVec3, width: u32, height: u32) -> HorizonResult {
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
        if !self.valid || w == 0 || h == 0 || !view_proj.is_finite() {
            return fallback();
        }
        let Some(view) = View::new(view_proj, eye, w, h, self.scale) else {
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
    fn dead_rows(view: &View, c: usize, stack: &[(u32, NodeProj)]) -> u32 {
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

    fn add_occluder(
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

#[derive(Default)]
struct Scratch {
    /// (column, y, sign)
    cross: Vec<(u32, f64, i8)>,
    iv: Vec<(f64, f64)>,
    /// (column, lo, hi): rows within the margin of a boundary edge
    unc: Vec<(u32, f64, f64)>,
    /// robustly covered intervals of one column, bottom up
    pieces: Vec<(f64, f64)>,
    valid: Vec<bool>,
    /// boundary edges (global sample indices) of the current occluder union
    ue: Vec<[u32; 2]>,
    /// per tile: range in `pool` of the boundary edges it was credited with (empty = not drawn)
    tile_edges: Vec<(u32, u32)>,
    pool: Vec<[u32; 2]>,
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

#[cfg(test)]
mod tests {
    use super::*;
    use glam::dcamera::rh::proj::{directx as dx_proj, opengl as gl_proj};
    use glam::dcamera::rh::view::look_at_mat4;
    use std::f64::consts::PI;

    use crate::TestRng as Lcg;

    struct Terrain {
        z: Vec<f32>,
        nx: usize,
        ny: usize,
        x0: f64,
        y0: f64,
        dx: f64,
        dy: f64,
        tiles: (usize, usize),
    }
    impl Terrain {
        fn grid(&self) -> HeightGrid<'_> {
            HeightGrid {
                z: &self.z,
                nx: self.nx,
                ny: self.ny,
                x0: self.x0,
                y0: self.y0,
                dx: self.dx,
                dy: self.dy,
                tiles: self.tiles,
            }
        }
        fn zmax(&self) -> f64 {
            self.z.iter().filter(|v| v.is_finite()).fold(f64::NEG_INFINITY, |a, &b| a.max(b as f64))
        }
        fn zmin(&self) -> f64 {
            self.z.iter().filter(|v| v.is_finite()).fold(f64::INFINITY, |a, &b| a.min(b as f64))
        }
        fn extent(&self) -> (f64, f64) {
            ((self.nx - 1) as f64 * self.dx.abs(), (self.ny - 1) as f64 * self.dy.abs())
        }
    }

    struct RefOut {
        /// tile has >= 1 pixel where it is (within tolerance) the nearest surface
        visible: Vec<bool>,
        /// tile produces >= 1 fragment at all (depth ignored)
        has_frag: Vec<bool>,
    }

    fn clip_poly(poly: &[DVec4], gl: bool) -> Vec<DVec4> {
        let mut p = poly.to_vec();
        for plane in 0..2 {
            let d = |v: &DVec4| {
                if plane == 0 {
                    if gl {
                        v.z + v.w
                    } else {
                        v.z
                    }
                } else {
                    v.w - v.z
                }
            };
            let mut out = Vec::with_capacity(p.len() + 2);
            for k in 0..p.len() {
                let a = p[k];
                let b = p[(k + 1) % p.len()];
                let (da, db) = (d(&a), d(&b));
                if da >= 0.0 {
                    out.push(a);
                }
                if (da >= 0.0) != (db >= 0.0) {
                    let t = da / (da - db);
                    out.push(a + (b - a) * t);
                }
            }
            p = out;
            if p.is_empty() {
                break;
            }
        }
        p
    }

    /// Software rasterizer: pixel-centre sampling (inclusive edges, generous), z-buffer.
    /// `reverse`: reverse-Z depth (larger z_ndc = nearer, as the renderer's `Greater` test).
    fn reference(t: &Terrain, vp: DMat4, w: usize, h: usize, gl: bool, reverse: bool) -> RefOut {
        let (tx, ty) = t.tiles;
        let bx = crate::lod::tile_bounds(t.nx, tx);
        let by = crate::lod::tile_bounds(t.ny, ty);
        let pos =
            |i: usize, j: usize| DVec3::new(t.x0 + i as f64 * t.dx, t.y0 + j as f64 * t.dy, t.z[j * t.nx + i] as f64);
        // collect screen-space triangles with tile id
        let mut tris: Vec<(usize, [DVec3; 3])> = Vec::new();
        for iy in 0..ty {
            for ix in 0..tx {
                let tile = iy * tx + ix;
                for j in by[iy]..by[iy + 1] {
                    for i in bx[ix]..bx[ix + 1] {
                        let a = pos(i, j);
                        let b = pos(i + 1, j);
                        let c = pos(i + 1, j + 1);
                        let d = pos(i, j + 1);
                        for tri in [[a, b, c], [a, c, d]] {
                            if tri.iter().any(|p| !p.z.is_finite()) {
                                continue;
                            }
                            let cl: Vec<DVec4> = tri.iter().map(|p| vp * p.extend(1.0)).collect();
                            let poly = clip_poly(&cl, gl);
                            if poly.len() < 3 || poly.iter().any(|c| c.w <= 1e-300) {
                                continue;
                            }
                            let sp: Vec<DVec3> = poly
                                .iter()
                                .map(|c| {
                                    DVec3::new(
                                        (c.x / c.w + 1.0) * 0.5 * w as f64,
                                        (c.y / c.w + 1.0) * 0.5 * h as f64,
                                        if reverse { -c.z / c.w } else { c.z / c.w },
                                    )
                                })
                                .collect();
                            for k in 1..sp.len() - 1 {
                                tris.push((tile, [sp[0], sp[k], sp[k + 1]]));
                            }
                        }
                    }
                }
            }
        }
        let raster = |tri: &[DVec3; 3], f: &mut dyn FnMut(usize, f64)| {
            let [a, b, c] = *tri;
            let area = (b.x - a.x) * (c.y - a.y) - (b.y - a.y) * (c.x - a.x);
            if area.abs() < 1e-14 {
                return;
            }
            let minx = a.x.min(b.x).min(c.x);
            let maxx = a.x.max(b.x).max(c.x);
            let miny = a.y.min(b.y).min(c.y);
            let maxy = a.y.max(b.y).max(c.y);
            let px0 = (minx - 0.5 - 1e-3).ceil().max(0.0);
            let px1 = (maxx - 0.5 + 1e-3).floor().min(w as f64 - 1.0);
            let py0 = (miny - 0.5 - 1e-3).ceil().max(0.0);
            let py1 = (maxy - 0.5 + 1e-3).floor().min(h as f64 - 1.0);
            if px0 > px1 || py0 > py1 {
                return;
            }
            let edge = |p: DVec3, q: DVec3, x: f64, y: f64| (q.x - p.x) * (y - p.y) - (q.y - p.y) * (x - p.x);
            for py in py0 as usize..=py1 as usize {
                for px in px0 as usize..=px1 as usize {
                    let (x, y) = (px as f64 + 0.5, py as f64 + 0.5);
                    let l0 = edge(b, c, x, y) / area;
                    let l1 = edge(c, a, x, y) / area;
                    let l2 = edge(a, b, x, y) / area;
                    let tol = -1e-7;
                    if l0 >= tol && l1 >= tol && l2 >= tol {
                        f(py * w + px, l0 * a.z + l1 * b.z + l2 * c.z);
                    }
                }
            }
        };
        let mut zbuf = vec![f64::INFINITY; w * h];
        for (_, tri) in &tris {
            raster(tri, &mut |i, d| {
                if d < zbuf[i] {
                    zbuf[i] = d;
                }
            });
        }
        let mut visible = vec![false; tx * ty];
        let mut has_frag = vec![false; tx * ty];
        for (tile, tri) in &tris {
            raster(tri, &mut |i, d| {
                has_frag[*tile] = true;
                if d <= zbuf[i] + 1e-12 {
                    visible[*tile] = true;
                }
            });
        }
        RefOut { visible, has_frag }
    }

    fn camera(eye: DVec3, fwd: DVec3, up: DVec3, ext: f64, w: usize, h: usize) -> DMat4 {
        let view = look_at_mat4(eye, eye + fwd, up);
        let proj = dx_proj::perspective(60f64.to_radians(), w as f64 / h as f64, 0.002 * ext, 20.0 * ext);
        proj * view
    }

    fn dir(az_deg: f64, pitch_deg: f64) -> DVec3 {
        let (a, p) = (az_deg.to_radians(), pitch_deg.to_radians());
        DVec3::new(p.cos() * a.cos(), p.cos() * a.sin(), p.sin())
    }

    struct Check {
        res: HorizonResult,
        rf: RefOut,
        violations: Vec<usize>,
        nonempty: usize,
        culled: usize,
        invisible: usize,
    }

    fn check_gl(t: &Terrain, vp: DMat4, eye: DVec3, w: usize, h: usize, gl: bool) -> Check {
        check_depth(t, vp, eye, w, h, gl, false)
    }

    fn check_depth(t: &Terrain, vp: DMat4, eye: DVec3, w: usize, h: usize, gl: bool, reverse: bool) -> Check {
        let tree = HorizonTree::build(&t.grid());
        let res = tree.cull(vp, eye, w as u32, h as u32);
        let rf = reference(t, vp, w, h, gl, reverse);
        let n = t.tiles.0 * t.tiles.1;
        let mut violations = vec![];
        let (mut nonempty, mut culled, mut invisible) = (0, 0, 0);
        for i in 0..n {
            if rf.visible[i] && !res.tile_visible[i] {
                violations.push(i);
            }
            if tree.tile_nonempty[i] {
                nonempty += 1;
                if !res.tile_visible[i] {
                    culled += 1;
                }
                if !rf.visible[i] {
                    invisible += 1;
                }
            }
        }
        Check { res, rf, violations, nonempty, culled, invisible }
    }

    fn check(t: &Terrain, vp: DMat4, eye: DVec3, w: usize, h: usize) -> Check {
        check_gl(t, vp, eye, w, h, false)
    }

    fn print_tiles(t: &Terrain, c: &Check) {
        let (tx, ty) = t.tiles;
        for iy in (0..ty).rev() {
            let row: String = (0..tx)
                .map(|ix| {
                    let i = iy * tx + ix;
                    match (c.res.tile_visible[i], c.rf.visible[i]) {
                        (true, true) => 'V',   // kept, visible
                        (true, false) => 'k',  // kept, invisible
                        (false, false) => '.', // culled, invisible
                        (false, true) => '!',  // culled but visible: BUG
                    }
                })
                .collect();
            println!("  iy={iy}: {row}");
        }
    }

    #[test]
    fn ridge_hides_valley() {
        let (nx, ny) = (65, 65);
        let mut z = vec![0f32; nx * ny];
        for j in 0..ny {
            for i in 0..nx {
                let y = j as f64;
                z[j * nx + i] = (12.0 * (-((y - 20.0) / 4.0).powi(2)).exp()
                    + 0.3 * (i as f64 * 0.7).sin() * (y * 0.5).cos()
                    + 0.3) as f32;
            }
        }
        let t = Terrain { z, nx, ny, x0: 0.0, y0: 0.0, dx: 1.0, dy: 1.0, tiles: (8, 8) };
        let (w, h) = (160, 120);
        let eye = DVec3::new(32.0, -20.0, 6.0);
        let vp = camera(eye, dir(90.0, -5.0), DVec3::Z, 64.0, w, h);
        let c = check(&t, vp, eye, w, h);
        println!(
            "ridge: culled {}/{} (reference-invisible {}), visited {}, culled nodes {}",
            c.culled, c.nonempty, c.invisible, c.res.nodes_visited, c.res.nodes_culled
        );
        print_tiles(&t, &c);
        assert!(c.res.culling_applied);
        assert!(c.violations.is_empty(), "visible tiles culled: {:?}", c.violations);
        // the valley behind the ridge (rows iy >= 4) must be culled, centre columns included
        for iy in 4..8 {
            for ix in 0..8 {
                let i = iy * 8 + ix;
                assert!(!c.rf.visible[i]);
                assert!(!c.res.tile_visible[i], "tile ({ix},{iy}) not culled");
            }
        }
        // the ridge itself is visible and kept
        for ix in 3..5 {
            assert!(c.res.tile_visible[2 * 8 + ix]);
        }
    }

    #[test]
    fn flat_field_only_frustum_culls() {
        let (nx, ny) = (65, 65);
        let t = Terrain { z: vec![0.0; nx * ny], nx, ny, x0: -10.0, y0: 5.0, dx: 1.0, dy: 1.0, tiles: (8, 8) };
        let (w, h) = (160, 120);
        for (k, (ex, ey, az, pitch)) in
            [(22.0, 37.0, 30.0, 0.0), (22.0, 37.0, 200.0, -10.0), (-30.0, 0.0, 45.0, -5.0), (10.0, 30.0, 90.0, -25.0)]
                .into_iter()
                .enumerate()
        {
            let eye = DVec3::new(ex, ey, 5.0);
            let vp = camera(eye, dir(az, pitch), DVec3::Z, 64.0, w, h);
            let c = check(&t, vp, eye, w, h);
            println!("flat {k}: culled {}/{}, reference-invisible {}", c.culled, c.nonempty, c.invisible);
            print_tiles(&t, &c);
            assert!(c.res.culling_applied);
            assert!(c.violations.is_empty(), "visible tiles culled: {:?}", c.violations);
            for i in 0..64 {
                if !c.res.tile_visible[i] {
                    assert!(!c.rf.has_frag[i], "tile {i} culled although inside the frustum");
                }
            }
        }
    }

    fn random_terrain(rng: &mut Lcg) -> Terrain {
        let nx = rng.irange(33, 65);
        let ny = rng.irange(33, 65);
        let tiles = (rng.irange(4, 8), rng.irange(4, 8));
        let dx = rng.range(0.5, 2.0);
        let dy = dx * rng.range(0.8, 1.25);
        let x0 = rng.range(-100.0, 100.0);
        let y0 = rng.range(-100.0, 100.0);
        let ext = ((nx - 1) as f64 * dx).max((ny - 1) as f64 * dy);
        let nw = rng.irange(1, 4);
        let waves: Vec<(f64, f64, f64, f64)> = (0..nw)
            .map(|_| {
                (
                    ext * rng.range(0.01, 0.12),
                    2.0 * PI / (ext * rng.range(0.15, 1.2)),
                    rng.range(0.0, 2.0 * PI),
                    rng.range(0.0, 2.0 * PI),
                )
            })
            .collect();
        let base = rng.range(-20.0, 20.0);
        let mut z = vec![0f32; nx * ny];
        for j in 0..ny {
            for i in 0..nx {
                let (x, y) = (i as f64 * dx, j as f64 * dy);
                let v: f64 =
                    waves.iter().map(|&(a, k, th, ph)| a * (k * (x * th.cos() + y * th.sin()) + ph).sin()).sum();
                z[j * nx + i] = (base + v) as f32;
            }
        }
        // holes
        let nh = rng.irange(0, 3);
        let noholes = std::env::var("NOHOLES").is_ok();
        for _ in 0..if noholes { 0 } else { nh } {
            let (ci, cj) = (rng.range(0.0, nx as f64), rng.range(0.0, ny as f64));
            let r = rng.range(0.8, 6.0);
            for j in 0..ny {
                for i in 0..nx {
                    if (i as f64 - ci).powi(2) + (j as f64 - cj).powi(2) < r * r {
                        z[j * nx + i] = f32::NAN;
                    }
                }
            }
        }
        let p = rng.range(0.0, 0.01);
        for v in z.iter_mut() {
            if rng.f() < p && !noholes {
                *v = f32::NAN;
            }
        }
        let mut t = Terrain { z, nx, ny, x0, y0, dx, dy, tiles };
        if rng.f() < 0.15 && !noholes {
            // an all-NaN tile
            let bx = crate::lod::tile_bounds(nx, tiles.0);
            let by = crate::lod::tile_bounds(ny, tiles.1);
            let (ix, iy) = (rng.irange(0, tiles.0 - 1), rng.irange(0, tiles.1 - 1));
            for j in by[iy]..=by[iy + 1] {
                for i in bx[ix]..=bx[ix + 1] {
                    t.z[j * nx + i] = f32::NAN;
                }
            }
        }
        t
    }

    #[test]
    fn property_random_low_cameras() {
        let mut rng = Lcg(0x1234_5678_9abc_def0);
        let (w, h) = (160, 120);
        let (mut sum_frac, mut sum_eff, mut n_eff) = (0.0, 0.0, 0);
        let (mut tot_culled, mut tot_nonempty, mut tot_invisible) = (0, 0, 0);
        let mut failures = vec![];
        let ncases: usize = std::env::var("HORIZON_CASES").ok().and_then(|v| v.parse().ok()).unwrap_or(200);
        let mut occl = 0usize;
        for case in 0..ncases {
            let t = random_terrain(&mut rng);
            let (ex, ey) = t.extent();
            let ext = ex.max(ey);
            let eye = DVec3::new(
                t.x0 + rng.range(-0.3, 1.3) * ex,
                t.y0 + rng.range(-0.3, 1.3) * ey,
                t.zmax() + rng.range(0.02, 0.30) * ext,
            );
            let az = if rng.f() < 0.5 {
                rng.range(0.0, 360.0)
            } else {
                let c = DVec3::new(t.x0 + 0.5 * ex, t.y0 + 0.5 * ey, 0.0) - eye;
                c.y.atan2(c.x).to_degrees() + rng.range(-45.0, 45.0)
            };
            let pitch = rng.range(-30.0, 5.0);
            let vp = camera(eye, dir(az, pitch), DVec3::Z, ext, w, h);
            let c = check(&t, vp, eye, w, h);
            assert!(c.res.culling_applied);
            if !c.violations.is_empty() {
                println!("case {case}: VIOLATION tiles {:?}", c.violations);
                print_tiles(&t, &c);
                failures.push(case);
            }
            sum_frac += c.culled as f64 / c.nonempty.max(1) as f64;
            if c.invisible > 0 {
                sum_eff += c.culled as f64 / c.invisible as f64;
                n_eff += 1;
            }
            tot_culled += c.culled;
            tot_nonempty += c.nonempty;
            tot_invisible += c.invisible;
            occl += (0..c.res.tile_visible.len()).filter(|&i| !c.res.tile_visible[i] && c.rf.has_frag[i]).count();
        }
        let nc = ncases as f64;
        println!(
            "property: {ncases} cases, tiles culled by occlusion (inside the frustum): {occl} = {:.3} of non-empty",
            occl as f64 / tot_nonempty as f64
        );
        println!(
            "property: mean culled fraction {:.3} (total {}/{} = {:.3}); reference-invisible {:.3}; mean culled/invisible {:.3} over {} cases",
            sum_frac / nc,
            tot_culled,
            tot_nonempty,
            tot_culled as f64 / tot_nonempty as f64,
            tot_invisible as f64 / tot_nonempty as f64,
            sum_eff / n_eff.max(1) as f64,
            n_eff
        );
        assert!(failures.is_empty(), "violations in cases {failures:?}");
    }

    /// Extra: roll, any pitch within the allowed range, orthographic views, eye anywhere.
    #[test]
    fn property_roll_ortho_any_eye() {
        let mut rng = Lcg(42);
        let (w, h) = (128, 96);
        let (mut culled, mut nonempty, mut applied) = (0, 0, 0);
        let ncases: usize = std::env::var("HORIZON_CASES").ok().and_then(|v| v.parse().ok()).unwrap_or(120);
        for case in 0..ncases {
            let t = random_terrain(&mut rng);
            let (ex, ey) = t.extent();
            let ext = ex.max(ey);
            let eye = DVec3::new(
                t.x0 + rng.range(-0.5, 1.5) * ex,
                t.y0 + rng.range(-0.5, 1.5) * ey,
                rng.range(t.zmin() - 0.1 * ext, t.zmax() + 0.5 * ext),
            );
            let f = dir(rng.range(0.0, 360.0), rng.range(-70.0, 70.0));
            let roll = rng.range(-40.0f64, 40.0).to_radians();
            let right = f.cross(DVec3::Z).normalize();
            let up0 = right.cross(f);
            let up = up0 * roll.cos() + right * roll.sin();
            let view = look_at_mat4(eye, eye + f, up);
            let gl = case % 4 == 1;
            let proj = if case % 3 == 0 {
                let s = rng.range(0.2, 0.8) * ext;
                let (l, r) = (-s * w as f64 / h as f64, s * w as f64 / h as f64);
                if gl {
                    gl_proj::orthographic(l, r, -s, s, 0.0, 4.0 * ext)
                } else {
                    dx_proj::orthographic(l, r, -s, s, 0.0, 4.0 * ext)
                }
            } else {
                let fov = rng.range(20.0f64, 90.0).to_radians();
                if gl {
                    gl_proj::perspective(fov, w as f64 / h as f64, 0.002 * ext, 20.0 * ext)
                } else {
                    dx_proj::perspective(fov, w as f64 / h as f64, 0.002 * ext, 20.0 * ext)
                }
            };
            let vp = proj * view;
            let c = check_gl(&t, vp, eye, w, h, gl);
            if c.res.culling_applied {
                applied += 1;
            }
            if !c.violations.is_empty() {
                print_tiles(&t, &c);
            }
            assert!(c.violations.is_empty(), "case {case}: visible tiles culled {:?}", c.violations);
            culled += c.culled;
            nonempty += c.nonempty;
        }
        println!("roll/ortho/any-eye: applied in {applied}/{ncases} views, culled {culled}/{nonempty}");
    }

    /// The renderer's projections: reverse-Z, infinite-far perspective and reverse-Z
    /// orthographic (near -> depth 1), low eyes near the terrain, `Greater` depth test.
    #[test]
    fn property_reverse_z() {
        let mut rng = Lcg(2024);
        let (w, h) = (128, 96);
        let (mut culled, mut nonempty, mut applied, mut ortho_culled) = (0, 0, 0, 0);
        let ncases: usize = std::env::var("HORIZON_CASES").ok().and_then(|v| v.parse().ok()).unwrap_or(160);
        for case in 0..ncases {
            let t = random_terrain(&mut rng);
            let (ex, ey) = t.extent();
            let ext = ex.max(ey);
            let eye = DVec3::new(
                t.x0 + rng.range(-0.3, 1.3) * ex,
                t.y0 + rng.range(-0.3, 1.3) * ey,
                t.zmax() + rng.range(0.005, 0.2) * ext,
            );
            let f = dir(rng.range(0.0, 360.0), rng.range(-30.0, 8.0));
            let view = look_at_mat4(eye, eye + f, DVec3::Z);
            let ortho = case % 3 == 0;
            let proj = if ortho {
                let s = rng.range(0.05, 0.5) * ext;
                let (l, r) = (-s * w as f64 / h as f64, s * w as f64 / h as f64);
                let near = if case % 2 == 0 { 0.0 } else { rng.range(0.0, 0.3) * ext };
                dx_proj::orthographic(l, r, -s, s, 4.0 * ext, near)
            } else {
                let fov = rng.range(20.0f64, 90.0).to_radians();
                let near = rng.range(0.0005, 0.05) * ext;
                dx_proj::perspective_infinite_reverse(fov, w as f64 / h as f64, near)
            };
            let vp = proj * view;
            let c = check_depth(&t, vp, eye, w, h, false, true);
            if c.res.culling_applied {
                applied += 1;
            }
            if !c.violations.is_empty() {
                print_tiles(&t, &c);
            }
            assert!(c.violations.is_empty(), "case {case} (ortho {ortho}): visible tiles culled {:?}", c.violations);
            culled += c.culled;
            nonempty += c.nonempty;
            if ortho {
                ortho_culled += c.culled;
            }
        }
        println!(
            "reverse-Z: applied in {applied}/{ncases} views, culled {culled}/{nonempty} (orthographic {ortho_culled})"
        );
        assert!(culled > 0 && ortho_culled > 0);
    }

    #[test]
    fn straight_down_and_below_terrain() {
        let mut rng = Lcg(7);
        let t = random_terrain(&mut rng);
        let (ex, ey) = t.extent();
        let ext = ex.max(ey);
        let (w, h) = (128, 96);
        let centre = DVec3::new(t.x0 + 0.5 * ex, t.y0 + 0.5 * ey, 0.0);
        // straight down
        let eye = DVec3::new(centre.x, centre.y, t.zmax() + 0.5 * ext);
        let vp = camera(eye, -DVec3::Z, DVec3::Y, ext, w, h);
        let tree = HorizonTree::build(&t.grid());
        let r = tree.cull(vp, eye, w as u32, h as u32);
        assert!(!r.culling_applied);
        assert_eq!(r.tile_visible, tree.tile_nonempty);
        assert_eq!(r.horizon.len(), w);
        // eye below the terrain, looking in several directions
        for (az, pitch) in [(0.0, 0.0), (90.0, 20.0), (200.0, -20.0), (300.0, 45.0)] {
            let eye = DVec3::new(centre.x, centre.y, t.zmin() - 0.05 * ext);
            let vp = camera(eye, dir(az, pitch), DVec3::Z, ext, w, h);
            let c = check(&t, vp, eye, w, h);
            println!("below ({az},{pitch}): applied {} culled {}/{}", c.res.culling_applied, c.culled, c.nonempty);
            assert!(c.violations.is_empty(), "visible tiles culled: {:?}", c.violations);
        }
        // degenerate inputs: no panic
        let _ = tree.cull(DMat4::ZERO, eye, w as u32, h as u32);
        let _ = tree.cull(vp, eye, 0, 0);
        let _ = tree.cull(DMat4::from_cols_array(&[f64::NAN; 16]), eye, 10, 10);
        let empty =
            HorizonTree::build(&HeightGrid { z: &[], nx: 0, ny: 0, x0: 0.0, y0: 0.0, dx: 1.0, dy: 1.0, tiles: (2, 2) });
        let r = empty.cull(vp, eye, 8, 8);
        assert!(!r.culling_applied && r.tile_visible.len() == 4);
    }
}
