//! The map pass's walk on the host: iso.wgsl `cs_map`, step for step, for adapters that are
//! CPUs themselves (lavapipe, llvmpipe). Its contract is the shader's: per pixel, the occlusion
//! map's depth (reverse-Z, 0 where nothing is proven) and the 4-bit marks of the march cells the
//! ray entered (`passes::march`), which `seen::seen_cells` resolves alike.
//!
//! Why a second copy of the walk: a CPU rasteriser runs the shader on SIMD lanes with every
//! branch of the loop taken for every lane, and reads storage buffers one lane at a time; the
//! same walk compiled for the host's cores steps each ray by itself, takes only its own branches
//! and reads the node bytes with plain loads. The two are kept alike by the tests
//! (`tests/test_iso.py`: both walks against `culling = "none"`; here, the cells seen per node and
//! the maps compared on a wavy field, noise with NaN samples, a sphere and a volume with whole
//! 64³ bricks). Crossings use unfused multiply-adds (the shader's `fma`): what matters is that a
//! brick jump and single steps compute them alike, which they do within each walk.
//!
//! What only the host's walk does, each exact (the cells seen and the map are the shader's):
//! nodes of skippable bricks come from a table of their bytes (`bricks::skip_byte`, cached
//! where the 32 MB of the frog's nodes are not); a cell of a skippable brick marks no near
//! event (every cell around it is of the brick's class, so the event would mark nothing); and
//! a coarse jump extends to a third level of skip bricks, 64³ nodes with their ring
//! (`bricks::pack_nodes` with `huge`), through which the cell-by-cell walk would mark nothing
//! and never stop, as through the two levels the shader knows; and where the ray leaves it
//! later, a jump takes instead the box of skippable bricks of the class about the current one
//! (`bricks::skip_reach`, a Chebyshev distance over the bricks: not aligned as the levels are).

use std::sync::atomic::{AtomicU32, Ordering};

use glam::{BVec3, IVec3, Mat4, UVec3, Vec3, Vec3A, Vec4};
use rayon::prelude::*;

use super::bricks::{brick_index, HUGE_SHIFT};
use super::passes::MapParams;

/// What the walk reads: the occluder nodes (one byte each in bricks of 4³, `bricks::pack_nodes`)
/// and, with contours, the contour bricks' words (`bricks::contour_bricks`: the table, then the
/// sample blocks from `MapParams::contour[0]`).
pub(super) struct WalkGrid<'a> {
    pub(super) nodes: &'a [u8],
    /// Per brick of 4³ nodes, the byte of each of its nodes when it is a skippable brick, else 0
    /// (`bricks::skip_byte`).
    pub(super) skip: &'a [u8],
    /// The third level of skip bricks (`2^HUGE_SHIFT` nodes per axis, `bricks::pack_nodes` with
    /// `huge`): a brick's class where it and its ring are all of it, else 0; and their dims.
    pub(super) huge: (&'a [u8], [u32; 3]),
    /// Per skippable brick of 4³ nodes, how far bricks of its class reach about it
    /// (`bricks::skip_reach`: a box of `2 r - 1` bricks per axis), else 0; empty: none.
    pub(super) reach: &'a [u8],
    pub(super) contour: Option<&'a [u32]>,
}

/// What a walk did: the rays that entered the volume's box (with its margin) and the steps they
/// took, a step being one cell entered or one jump across skippable bricks (each ray's first cell
/// counting one).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct WalkCounts {
    pub rays: u64,
    pub steps: u64,
}

/// The walk of every pixel of a `width` × `height` image: `(marks, map, counts)`, the marks of the
/// `n_cells` march cells (8 per word, as `passes::march` returns them), the map's depth per
/// pixel (row-major, row 0 = top) and what the walk did. `view_proj` is the frame's (f32, as the
/// shader's `Globals`).
pub(super) fn walk(
    p: &MapParams,
    view_proj: &Mat4,
    grid: &WalkGrid,
    width: u32,
    height: u32,
    n_cells: usize,
) -> (Vec<u32>, Vec<f32>, WalkCounts) {
    let marks: Vec<AtomicU32> = (0..n_cells.div_ceil(8).max(1)).map(|_| AtomicU32::new(0)).collect();
    let mut map = vec![0.0f32; (width * height) as usize];
    let w = Walker::new(p, view_proj, grid, &marks);
    let counts = map
        .par_chunks_mut(width as usize)
        .enumerate()
        .map(|(y, row)| {
            let mut c = WalkCounts::default();
            for (x, out) in row.iter_mut().enumerate() {
                let mut steps = 0;
                *out = w.ray(x as u32, y as u32, &mut steps);
                c.rays += u64::from(steps > 0);
                c.steps += u64::from(steps);
            }
            c
        })
        .reduce(WalkCounts::default, |a, b| WalkCounts { rays: a.rays + b.rays, steps: a.steps + b.steps });
    (marks.into_iter().map(AtomicU32::into_inner).collect(), map, counts)
}

fn v3(v: [f32; 4]) -> Vec3 {
    Vec3::new(v[0], v[1], v[2])
}

/// Where the ray leaves cell index `c` along one axis, `t0 + c dt` (unfused): every crossing the
/// walk compares, single steps' and brick jumps' alike, comes from here, so they agree bit for bit.
#[inline]
fn exit(c: i32, t0: f32, dt: f32) -> f32 {
    c as f32 * dt + t0
}

fn pick(m: BVec3, a: Vec3, b: Vec3) -> Vec3 {
    Vec3::select(m, a, b)
}

/// Per-frame constants of the walk.
struct Walker<'a> {
    p: &'a MapParams,
    view_proj: &'a Mat4,
    grid: &'a WalkGrid<'a>,
    marks: &'a [AtomicU32],
    lo: Vec3,
    hi: Vec3,
    node: Vec3,
    dims: IVec3,
    margin: f32,
    contours: bool,
}

impl<'a> Walker<'a> {
    fn new(p: &'a MapParams, view_proj: &'a Mat4, grid: &'a WalkGrid<'a>, marks: &'a [AtomicU32]) -> Self {
        Walker {
            p,
            view_proj,
            grid,
            marks,
            lo: v3(p.lo),
            hi: v3(p.hi),
            node: v3(p.node),
            dims: IVec3::new(p.dims[0] as i32, p.dims[1] as i32, p.dims[2] as i32),
            margin: p.hi[3],
            contours: grid.contour.is_some() && p.contour[0] != 0,
        }
    }

    /// iso.wgsl `mark_cell`.
    #[inline]
    fn mark_cell(&self, c: IVec3, bits: u32) {
        if self.p.size[3] == 1 {
            let [x, y, z] = c.to_array().map(|v| v as usize);
            let i = (z * self.p.dims[1] as usize + y) * self.p.dims[0] as usize + x;
            let b = bits << ((i & 7) * 4);
            let word = &self.marks[i >> 3];
            if word.load(Ordering::Relaxed) & b != b {
                word.fetch_or(b, Ordering::Relaxed);
            }
        }
    }

    /// iso.wgsl `node_info`, from the skippable bricks' table where it holds the node.
    #[inline]
    fn node_info(&self, c: IVec3) -> u32 {
        let [x, y, z, _] = self.p.occ_dims;
        let i = brick_index([x, y, z], (c.as_uvec3() >> self.p.size[1]).to_array());
        // (Its brick is byte `i / 64`'s.)
        match self.grid.skip[i >> 6] {
            0 => self.grid.nodes[i] as u32,
            t => t as u32,
        }
    }

    /// The class of the third-level skip brick holding march cell `c` when it is skippable, else 0.
    #[inline]
    fn huge_class(&self, c: IVec3) -> u32 {
        let (classes, [hx, hy, _]) = self.grid.huge;
        let u = (c.as_uvec3() >> (self.p.size[1] + HUGE_SHIFT)).to_array().map(|v| v as usize);
        classes.get((u[2] * hy as usize + u[1]) * hx as usize + u[0]).map_or(0, |&k| k as u32)
    }

    /// [`WalkGrid::reach`] of the brick of 4³ nodes holding march cell `c` (0 without the table).
    #[inline]
    fn reach(&self, c: IVec3) -> i32 {
        if self.grid.reach.is_empty() {
            return 0;
        }
        let [x, y, _, _] = self.p.occ_dims;
        let b = (c.as_uvec3() >> (self.p.size[1] + 2)).to_array().map(|v| v as usize);
        let (bx, by) = (x.div_ceil(4) as usize, y.div_ceil(4) as usize);
        self.grid.reach[(b[2] * by + b[1]) * bx + b[0]] as i32
    }

    /// iso.wgsl `contour_brick`.
    fn contour_brick(&self, c: IVec3) -> usize {
        let cb = (c.as_uvec3() >> 2u32).to_array().map(|v| v as usize);
        (cb[2] * self.p.contour[2] as usize + cb[1]) * self.p.contour[1] as usize + cb[0]
    }

    /// iso.wgsl `face_side`.
    fn face_side(&self, c: IVec3, a: usize, up: bool, gp: Vec3A, dg: Vec3A, block: u32) -> u32 {
        if block == u32::MAX {
            return 4;
        }
        let data = self.grid.contour.unwrap();
        let b = (a + 1) % 3;
        let e = (a + 2) % 3;
        let mut q = c.as_uvec3() & UVec3::splat(3);
        q[a] += if up { 0 } else { 1 };
        let st = UVec3::new(1, 5, 25);
        let i = self.p.contour[0] as usize + block as usize * 125 + q.dot(st) as usize;
        let (sb, se) = (st[b] as usize, st[e] as usize);
        let iso = f32::from_bits(self.p.contour[3]);
        let f = [data[i], data[i + sb], data[i + se], data[i + sb + se]].map(|s| f32::from_bits(s) - iso);
        contour_side(f, [gp[b] - c[b] as f32, gp[e] - c[e] as f32], [dg[b], dg[e], dg[a]], self.margin)
    }

    /// iso.wgsl `exits`: where the ray leaves cell `c` across each axis, [`exit`] per axis.
    #[inline]
    fn exits(c: IVec3, t0: Vec3, dt: Vec3) -> Vec3 {
        Vec3::new(exit(c.x, t0.x, dt.x), exit(c.y, t0.y, dt.y), exit(c.z, t0.z, dt.z))
    }

    /// Pixel `(x, y)`'s ray as the walk follows it (see [`Ray`]), its first march cell and that
    /// cell's exits per axis; None when it misses the volume's box (with the margin).
    #[inline]
    fn enter(&self, x: u32, y: u32) -> Option<(Ray, IVec3, Vec3)> {
        let p = self.p;
        let (w, h) = (p.dims[3], p.size[0]);
        let ndc = [(x as f32 + 0.5) / w as f32 * 2.0 - 1.0, 1.0 - (y as f32 + 0.5) / h as f32 * 2.0];
        let o = v3(p.ray_o) + ndc[0] * v3(p.ray_ox) + ndc[1] * v3(p.ray_oy);
        let mut d = v3(p.ray_d) + ndc[0] * v3(p.ray_dx) + ndc[1] * v3(p.ray_dy);
        let parallel = d.abs().cmplt(Vec3::splat(1e-30));
        d = pick(parallel, Vec3::splat(1e-30), d);
        let inv = 1.0 / d;
        let (lo, hi, node, dims) = (self.lo, self.hi, self.node, self.dims);
        let margin = self.margin * node;
        let ta = (lo - o) * inv;
        let tb = (hi - o) * inv;
        let in0 = ta.x.min(tb.x).max(ta.y.min(tb.y)).max(ta.z.min(tb.z).max(0.0));
        let in1 = ta.x.max(tb.x).min(ta.y.max(tb.y)).min(ta.z.max(tb.z));
        let tmin = ta.min(tb) - (margin * inv).abs();
        let tmax = ta.max(tb) + (margin * inv).abs();
        let t0 = tmin.x.max(tmin.y).max(tmin.z.max(0.0));
        let t1 = tmax.x.min(tmax.y).min(tmax.z);
        if t0 >= t1 || t0.is_nan() || t1.is_nan() {
            return None;
        }
        let pt = o + d * t0;
        let c = ((pt - lo) / node).floor().clamp(Vec3::ZERO, (dims - 1).as_vec3()).as_ivec3();
        let fwd = d.cmpgt(Vec3::ZERO);
        let stp = IVec3::select(fwd, IVec3::ONE, IVec3::NEG_ONE);
        let ahead = pick(fwd, Vec3::ONE, Vec3::ZERO);
        let xt0 = pick(parallel, Vec3::splat(1e30), (lo + ahead * node - o) * inv);
        let xdt = pick(parallel, Vec3::ZERO, node * inv);
        let tnext = Self::exits(c, xt0, xdt);
        // 1 / |dt| (+inf along a parallel axis, whose crossings are at 1e30).
        let rdt = 1.0 / xdt.abs();
        // (SIMD vectors for the per-step point arithmetic: each lane rounds as the scalar
        // operation does, so the results are the same bits.)
        let dg = Vec3A::from(d / node);
        let og = Vec3A::from((o - lo) / node);
        let ext = Vec3A::from((hi - lo) / node);
        let ray = Ray { o, d, in0, in1, t0, t1, stp, xt0, xdt, rdt, dg, og, ext };
        Some((ray, c, tnext))
    }

    /// iso.wgsl `cs_map` for pixel `(x, y)`: its map depth; marks as it goes and counts its
    /// `steps` (none when it misses the box).
    fn ray(&self, x: u32, y: u32, steps: &mut u32) -> f32 {
        let p = self.p;
        let Some((r, mut c, mut tnext)) = self.enter(x, y) else { return 0.0 };
        let Ray { o, d, in0, in1, t0, t1, stp, xt0, xdt, dg, og, ext, .. } = r;
        let hw = self.margin;
        let hw3 = Vec3A::splat(hw);
        let single = p.size[2] == 1;
        let mut last = 0u32;
        let mut t_enter = t0;
        let mut crossed: i32 = -1;
        let mut prev_info = 0u32;
        let mut stepped = false;
        let mut brick_at = usize::MAX;
        let mut brick = u32::MAX;
        loop {
            *steps += 1;
            let info = self.node_info(c);
            let k = info & 3;
            let ax = crossed.clamp(0, 2) as usize;
            let up = stp[ax] > 0;
            let owner = if up { info } else { prev_info };
            let uniform = (owner >> (4 + ax as u32)) & 1 == 1;
            let face_in = single && stepped && t_enter > in0 && t_enter < in1;
            let gp = dg * t_enter + og;
            let mut fk = if face_in && uniform {
                if owner & 128 != 0 {
                    1
                } else {
                    2
                }
            } else {
                0
            };
            if self.contours && face_in && !uniform {
                let cb = self.contour_brick(c);
                if cb != brick_at {
                    brick = self.grid.contour.unwrap()[cb];
                    brick_at = cb;
                }
                let side = self.face_side(c, ax, up, gp, dg, brick);
                if side != 4 {
                    fk = side;
                }
            }
            let at_box = (gp.abs().cmplt(hw3) | (gp - ext).abs().cmplt(hw3)).any();
            let mut stop = fk != 0 && last != 0 && last != fk && !at_box;
            if fk != 0 {
                last = fk;
            }
            let close = (gp - (gp + 0.5).floor()).abs().cmplt(hw3);
            // Near events: bits 1-3 (the crossed axis's plane is behind the ray).
            let behind = u32::from(crossed >= 0) * (2 << crossed.max(0));
            // (In a skippable brick every cell around is of the brick's class: nothing to mark.)
            let near = (close.bitmask() << 1) & !behind & if info & 4 != 0 { 0 } else { !0 };
            let bits = u32::from((k == 0 || k == 3) && !stop) | near;
            if bits != 0 {
                self.mark_cell(c, bits);
            }
            if k == 3 || (at_box && k == 0) || tnext.min_element() <= in0 || t_enter >= in1 {
                last = 0;
            } else if k != 0 {
                stop = stop || (last != 0 && last != k && !at_box);
                last = k;
            }
            if stop {
                let q = o + d * (t_enter + p.lo[3] / d.length());
                let clip = *self.view_proj * Vec4::new(q.x, q.y, q.z, 1.0);
                return (clip.z / clip.w).clamp(0.0, 1.0);
            }
            let skip = p.bricks[0] != 0 && last == k && k != 0 && info & 4 != 0;
            let tx;
            let a;
            if !skip {
                // One cell: its exits are `tnext`; only axis `a` advances (the shader's closed
                // form gives n = 0 for the others).
                let a01 = usize::from(tnext.y < tnext.x);
                a = if tnext.z < tnext.x.min(tnext.y) { 2 } else { a01 };
                tx = tnext[a];
                if tx >= t1 {
                    return 0.0;
                }
                c[a] += stp[a];
                tnext[a] = exit(c[a], xt0[a], xdt[a]);
            } else {
                let Some(jump) = self.skip_brick(&r, &mut c, &mut tnext, info, k) else { return 0.0 };
                (a, tx) = jump;
            }
            t_enter = tx;
            crossed = a as i32;
            prev_info = info;
            stepped = !skip;
            if c.cmplt(IVec3::ZERO).any() || c.cmpge(self.dims).any() {
                return 0.0;
            }
        }
    }

    /// A jump across the skippable brick of class `k` holding march cell `c` (`info`: its
    /// node's byte), or across the box of bricks of that class about it when the ray leaves that
    /// later: moves `c` to the cell it enters and `tnext` to that cell's exits. Returns the axis
    /// crossed and where, or None when the ray leaves the box first.
    #[inline]
    fn skip_brick(&self, r: &Ray, c: &mut IVec3, tnext: &mut Vec3, info: u32, k: u32) -> Option<(usize, f32)> {
        let p = self.p;
        let dims = self.dims;
        let Ray { t1, stp, xt0, xdt, rdt, .. } = *r;
        // (A coarse brick in a skippable third-level brick: that one's exit.)
        let level = match info & 8 != 0 {
            true if self.huge_class(*c) == k => HUGE_SHIFT,
            true => p.bricks[1],
            false => p.bricks[0],
        };
        let s = p.size[1] + level;
        let blo = (*c >> s as i32) << s as i32;
        let bhi = blo + IVec3::splat((1 << s) - 1);
        let mut e = IVec3::select(stp.cmpgt(IVec3::ZERO), bhi.min(dims - 1), blo);
        let mut xe = Self::exits(e, xt0, xdt);
        // (A box of bricks of the class about this one, when the ray leaves it later.)
        let rr = self.reach(*c);
        if rr >= 2 {
            let half = (rr - 1) << (p.size[1] + 2);
            let b = (*c >> (p.size[1] as i32 + 2)) << (p.size[1] as i32 + 2);
            let (rlo, rhi) = ((b - IVec3::splat(half)).max(IVec3::ZERO), b + IVec3::splat(half + (4 << p.size[1]) - 1));
            let re = IVec3::select(stp.cmpgt(IVec3::ZERO), rhi.min(dims - 1), rlo);
            let rxe = Self::exits(re, xt0, xdt);
            if rxe.min_element() > xe.min_element() {
                (e, xe) = (re, rxe);
            }
        }
        let a01 = usize::from(xe.y < xe.x);
        let a = if xe.z < xe.x.min(xe.y) { 2 } else { a01 };
        let tx = xe[a];
        if tx >= t1 {
            return None;
        }
        let most = (e - *c).abs();
        let mut n = IVec3::ZERO;
        for i in 0..3 {
            if i == a {
                continue;
            }
            let lower = i < a;
            // ceil((tx - tnext) / |dt|) within [0, most] (`max` drops a NaN).
            let est = ((tx - tnext[i]) * rdt[i]).max(0.0).min(most[i] as f32);
            let mut ni = est as i32;
            ni += i32::from((ni as f32) < est);
            let xb = exit(c[i] + (ni - 1) * stp[i], xt0[i], xdt[i]);
            if ni > 0 && !(xb < tx || (xb == tx && lower)) {
                ni -= 1;
            }
            let xn = exit(c[i] + ni * stp[i], xt0[i], xdt[i]);
            if ni < most[i] && (xn < tx || (xn == tx && lower)) {
                ni += 1;
            }
            n[i] = ni;
        }
        *c += n * stp;
        c[a] = e[a] + stp[a];
        *tnext = Self::exits(*c, xt0, xdt);
        Some((a, tx))
    }
}

/// A pixel's ray as the walk follows it ([`Walker::enter`]): origin and direction (render
/// space), where it enters and leaves the box (`in0`, `in1`) and the box with the margin (`t0`,
/// `t1`), its step per axis, the first cell crossings and their spacing per axis (`xt0`, `xdt`,
/// `rdt` = 1 / |`xdt`|), and in march cells its direction, origin and the box's extent.
#[derive(Clone, Copy)]
struct Ray {
    o: Vec3,
    d: Vec3,
    in0: f32,
    in1: f32,
    t0: f32,
    t1: f32,
    stp: IVec3,
    xt0: Vec3,
    xdt: Vec3,
    rdt: Vec3,
    dg: Vec3A,
    og: Vec3A,
    ext: Vec3A,
}

/// iso.wgsl `contour_side`: the side of the surface (1 = below, 2 = above, 0 = not known) of
/// point `uv` of a face whose corners (0, 0), (1, 0), (0, 1), (1, 1) have the values `f` minus
/// the isovalue; `ray` the ray's direction along u, v and the face's normal; `m` the margin.
fn contour_side(f: [f32; 4], uv: [f32; 2], ray: [f32; 3], m: f32) -> u32 {
    // (The four corners' terms in SIMD lanes: each lane rounds as the scalar operation would.)
    let fv = Vec4::from_array(f);
    if fv.cmpeq(Vec4::ZERO).any() {
        return 0;
    }
    let k = |i: u32| if f[i as usize] >= 0.0 { 2u32 } else { 1 };
    // Edges (corner pairs) 0-1, 2-3, 0-2, 1-3; crossed where their corners' signs differ.
    let ea = Vec4::new(f[0], f[2], f[0], f[1]);
    let eb = Vec4::new(f[1], f[3], f[2], f[3]);
    let cr = ea.cmpge(Vec4::ZERO) ^ eb.cmpge(Vec4::ZERO);
    let crm = cr.bitmask();
    if crm == 0 {
        return k(0);
    }
    let t = Vec4::select(cr, ea / (ea - eb), Vec4::splat(0.5)).to_array();
    let [u, v] = uv;
    let px = Vec4::new(u, 1.0 - u, u, 1.0 - u);
    let py = Vec4::new(v, v, 1.0 - v, 1.0 - v);
    let tx = Vec4::new(t[0], 1.0 - t[0], t[1], 1.0 - t[1]);
    let ty = Vec4::new(t[2], t[3], 1.0 - t[2], 1.0 - t[3]);
    let n2 = ray[2] * ray[2];
    let m2 = m * m;
    let sx = Vec4::new(ray[0], -ray[0], ray[0], -ray[0]);
    let sy = Vec4::new(ray[1], ray[1], -ray[1], -ray[1]);
    // Corner i is cut off when both its edges are crossed: corners 0, 1, 2, 3 lie on edges
    // (0, 2), (0, 3), (1, 2), (1, 3).
    let c = |e: u32| crm >> e & 1;
    let both = c(0) & c(2) | (c(0) & c(3)) << 1 | (c(1) & c(2)) << 2 | (c(1) & c(3)) << 3;
    let g = px * ty + py * tx - tx * ty;
    let qr = ty * sx + tx * sy;
    let far = (g * g * n2).cmpgt(m2 * (n2 * (tx * tx + ty * ty) + qr * qr)).bitmask();
    // In a cut-off corner's triangle (g < 0), far enough from its segment: that corner's side
    // (the lowest such corner).
    let inside = both & far & g.cmplt(Vec4::ZERO).bitmask();
    let mut r = if inside != 0 { k(inside.trailing_zeros()) } else { 0 };
    if both.count_ones() == 1 && both & far & g.cmpgt(Vec4::ZERO).bitmask() != 0 {
        r = 3 - k(both.trailing_zeros());
    }
    let sv = t[3] - t[2];
    let su = t[1] - t[0];
    let gv = v - t[2] - u * sv;
    let gu = u - t[0] - v * su;
    let qv = ray[1] - sv * ray[0];
    let qu = ray[0] - su * ray[1];
    let far_v = gv * gv * n2 > m2 * (n2 * (1.0 + sv * sv) + qv * qv);
    let far_u = gu * gu * n2 > m2 * (n2 * (1.0 + su * su) + qu * qu);
    // One segment across the face: from edge 2 to edge 3 (corner pairs 0-2 and 1-3; its sides
    // are low and high v), or from edge 0 to edge 1 (pairs 0-1 and 2-3; low and high u).
    if crm == 0b1100 && far_v {
        r = if gv < 0.0 { k(0) } else { k(2) };
    }
    if crm == 0b0011 && far_u {
        r = if gu < 0.0 { k(0) } else { k(1) };
    }
    r
}

#[cfg(test)]
mod tests;
