//! Projection for one frame: clip/screen coordinates, depth-range tests and the pixel error bounds
//! of the GPU's f32 arithmetic and sub-pixel snapping.

use glam::{DMat4, DVec3, DVec4};

use super::PIX_EPS;

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

pub(super) struct View {
    m: DMat4,
    /// |rows| of `m` (x, y, z, w), for the f32 error bound of clip coordinates
    ra: [DVec4; 4],
    /// homogeneous centre of projection (w = 1 perspective, w = 0 orthographic: -view dir)
    pub(super) eh: DVec4,
    pub(super) w_margin: f64,
    wf: f64,
    pub(super) hf: f64,
    pub(super) w: usize,
    pub(super) h: usize,
}

impl View {
    /// The view of a tree built in object-local coordinates: `m` maps render space to clip space,
    /// `offset` (render space) moves the tree's coordinates into render space, `eye` is in render
    /// space, `scale` is the tree's own coordinate scale. The GPU draws `p + offset` with an f32
    /// matrix, so the round-off bound (`ra`) keeps `|m| (|p| + |offset|)`: as large as for a tree
    /// built at its translated place, however the translation cancels in `m * T(offset)`.
    pub(super) fn new(m: DMat4, offset: DVec3, eye: DVec3, w: usize, h: usize, scale: f64) -> Option<View> {
        let ra = [0, 1, 2, 3].map(|i| {
            let r = m.row(i).abs();
            r.truncate().extend(r.w + r.truncate().dot(offset.abs()))
        });
        let (r3_render, scale) = (m.row(3), scale + offset.length());
        let m = m * DMat4::from_translation(offset);
        let eye = eye - offset;
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
        let w_margin = (1e-9 * (r3_render.truncate().length() * scale + r3_render.w.abs())).max(1e-300);
        Some(View { m, ra, eh, w_margin, wf: w as f64, hf: h as f64, w, h })
    }

    #[inline]
    pub(super) fn clip(&self, p: DVec3) -> DVec4 {
        self.m * p.extend(1.0)
    }

    #[inline]
    pub(super) fn screen(&self, c: DVec4) -> (f64, f64) {
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
    pub(super) fn err_px(&self, p: DVec3, c: DVec4) -> f64 {
        let ew = self.f32_err(3, p);
        let w_safe = c.w > ew + self.w_margin; // false for NaN too
        if !w_safe {
            return f64::INFINITY;
        }
        let ex = (self.f32_err(0, p) + (c.x / c.w).abs() * ew) / (c.w - ew);
        let ey = (self.f32_err(1, p) + (c.y / c.w).abs() * ew) / (c.w - ew);
        RASTER_EPS + PIX_EPS + (0.5 * self.wf * ex).max(0.5 * self.hf * ey)
    }

    /// Inside the depth range `0 <= z <= w` (wgpu/Vulkan/D3D; holds for standard and reverse-Z)
    /// with a margin for the GPU's f32 round-off, so the GPU does not clip it.
    #[inline]
    pub(super) fn in_depth(&self, p: DVec3, c: DVec4) -> bool {
        let (ez, ew) = (self.f32_err(2, p), self.f32_err(3, p));
        c.w > self.w_margin + ew && c.z >= ez && c.z <= c.w - ez - ew
    }

    /// Number of rows whose centre is < y (clamped to 0..=h).
    #[inline]
    pub(super) fn rows_below(&self, y: f64) -> u32 {
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
    pub(super) fn col_range(&self, xmin: f64, xmax: f64, eps: f64) -> Option<(usize, usize)> {
        let c0 = (xmin - eps - 0.5).ceil().max(0.0);
        let c1 = (xmax + eps - 0.5).floor().min(self.wf - 1.0);
        if c0 > c1 || c0.is_nan() || c1.is_nan() {
            None
        } else {
            Some((c0 as usize, c1 as usize))
        }
    }
}
