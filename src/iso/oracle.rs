//! `culling = "oracle"` for isosurfaces: the cells that hold a visible point of the unculled
//! image, about the least that any culling drawing whole cells (as `implicit` does) can draw, for
//! benchmarks. `IsoRenderer::render` renders the unculled image first (untimed) and reads each
//! pixel's surface point back from its depth ([`visible_cells`]). The point can lie in the wrong
//! cell: on a triangle seen nearly edge-on, the rasteriser's sub-pixel snapping moves the depth of
//! a pixel a long way along its ray. So the oracle's frame is compared with the unculled one, and
//! at every pixel that differs the cells along the ray about the point are taken too, over a
//! reach four times longer at each try ([`widen_where_wrong`]), until the images agree (or
//! [`ORACLE_TRIES`] frames have been drawn: the bench's diff column would show it). Only the last
//! frame's extraction and draw are timed: an oracle knows its cells.

use glam::DVec3;
use rayon::prelude::*;

use super::passes::PixelRays;

/// The most frames the oracle draws to find cells that give the unculled image.
pub(super) const ORACLE_TRIES: usize = 4;

/// The reference's depth per pixel (distance along the view axis, +inf where empty, row-major,
/// row 0 = top) and, per pixel, how far along its ray (grid units, either way) the cells about its
/// surface point are taken (0: the point's cell, and those across a face within the tolerance).
pub(super) struct OracleCells {
    pub(super) depth: Vec<f32>,
    pub(super) reach: Vec<f32>,
}

/// Where the oracle's `image` differs from the unculled `reference` (RGBA8 each), a reach along
/// the pixel's ray of 1 cell, or four times the last; returns the number of such pixels.
pub(super) fn widen_where_wrong(cells: &mut OracleCells, image: &[u8], reference: &[u8]) -> usize {
    let mut wrong = 0;
    for ((r, a), b) in cells.reach.iter_mut().zip(image.chunks_exact(4)).zip(reference.chunks_exact(4)) {
        if a != b {
            *r = if *r == 0.0 { 1.0 } else { 4.0 * *r };
            wrong += 1;
        }
    }
    wrong
}

/// The cells (one bit each, cell `i` is bit `i % 32` of word `i / 32`, x fastest) of a grid of
/// `dims` cells of `size` (render units) from `lo` that hold the surface point of a pixel of
/// `cells` (`width` × `height`), where its ray reaches the pixel's depth (the distance along the
/// view axis is affine along a ray). A point within `tol` (grid units) of a cell face marks the
/// cell across it too. With a reach `r`, the ray from `r` before the point to `r` beyond it marks
/// its cells (points every half cell, each with the cells within a quarter cell).
#[allow(clippy::too_many_arguments)]
pub(super) fn visible_cells(
    cells: &OracleCells,
    width: u32,
    height: u32,
    rays: &PixelRays,
    lo: DVec3,
    size: DVec3,
    dims: [u32; 3],
    tol: f64,
) -> Vec<u32> {
    use std::sync::atomic::{AtomicU32, Ordering};
    let n = dims.iter().map(|&v| v as usize).product::<usize>();
    let bits: Vec<AtomicU32> = (0..n.div_ceil(32)).map(|_| AtomicU32::new(0)).collect();
    let span = rays.far_dist - rays.near_dist;
    // The cells within `h` of grid point `g`, per axis.
    let mark = |g: DVec3, h: f64| {
        let range = |v: f64, n: u32| {
            let lo = ((v - h).floor().max(0.0) as i64).min(n as i64 - 1) as u32;
            let hi = ((v + h).floor().max(0.0) as i64).min(n as i64 - 1) as u32;
            lo..=hi
        };
        for k in range(g.z, dims[2]) {
            for j in range(g.y, dims[1]) {
                for i in range(g.x, dims[0]) {
                    let c = ((k * dims[1] + j) * dims[0] + i) as usize;
                    bits[c / 32].fetch_or(1 << (c % 32), Ordering::Relaxed);
                }
            }
        }
    };
    let w = width as usize;
    cells.depth.par_chunks(w).zip(cells.reach.par_chunks(w)).enumerate().for_each(|(y, (row, reach))| {
        let ndc_y = 1.0 - (y as f64 + 0.5) / height as f64 * 2.0;
        for (x, (&z, &r)) in row.iter().zip(reach).enumerate() {
            if !z.is_finite() {
                continue;
            }
            let ndc_x = (x as f64 + 0.5) / width as f64 * 2.0 - 1.0;
            let at = |p: &[DVec3; 3]| p[0] + ndc_x * p[1] + ndc_y * p[2];
            let (a, b) = (at(&rays.near), at(&rays.far));
            let g = (a + (b - a) * ((z as f64 - rays.near_dist) / span) - lo) / size;
            if r <= 0.0 {
                mark(g, tol);
                continue;
            }
            let u = ((b - a) / size).normalize_or_zero();
            let n = (2.0 * r as f64 / 0.5).ceil() as i32;
            for s in 0..=n {
                mark(g + u * (-(r as f64) + 0.5 * s as f64), 0.25f64.max(tol));
            }
        }
    });
    bits.into_iter().map(AtomicU32::into_inner).collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    /// An orthographic view straight down z onto a 4 × 4 × 4 grid of unit cells (the near plane
    /// z = 10 at distance 1, the far plane z = 0 at distance 11: a pixel's point at distance D is at
    /// height 11 - D): the cell under the pixel centre at that height, both cells across a face
    /// within the tolerance, a point below the grid clamped to its bottom cell.
    #[test]
    fn points_of_known_pixels() {
        // NDC (x, y) in [-1, 1]² covers the grid's x, y in [0, 4]²; near plane z = 10, far z = 0.
        let plane = |z: f64| [DVec3::new(2.0, 2.0, z), DVec3::new(2.0, 0.0, 0.0), DVec3::new(0.0, 2.0, 0.0)];
        let rays = PixelRays { near: plane(10.0), far: plane(0.0), near_dist: 1.0, far_dist: 11.0 };
        let cells = |depth: &[f32], reach: f32| OracleCells { depth: depth.to_vec(), reach: vec![reach; 16] };
        let (w, h) = (4, 4);
        let cell = |i: u32, j: u32, k: u32| ((k * 4 + j) * 4 + i) as usize;
        let set = |bits: &[u32]| -> Vec<usize> { (0..64).filter(|&c| bits[c / 32] >> (c % 32) & 1 == 1).collect() };
        // Pixel (1, 2) (x = 1.5, y = 4 - 2.5 = 1.5) at distance 8.5: z = 10 - 7.5 = 2.5 -> cell (1, 1, 2).
        let mut depth = vec![f32::INFINITY; 16];
        depth[2 * 4 + 1] = 8.5;
        let bits = visible_cells(&cells(&depth, 0.0), w, h, &rays, DVec3::ZERO, DVec3::ONE, [4, 4, 4], 0.01);
        assert_eq!(set(&bits), vec![cell(1, 1, 2)]);
        // At distance 9.0 (z = 2.0, on the face between k = 1 and k = 2): both.
        depth[2 * 4 + 1] = 9.0;
        let bits = visible_cells(&cells(&depth, 0.0), w, h, &rays, DVec3::ZERO, DVec3::ONE, [4, 4, 4], 0.01);
        assert_eq!(set(&bits), vec![cell(1, 1, 1), cell(1, 1, 2)]);
        // Points outside the grid clamp to its border cells; empty pixels mark nothing.
        depth[2 * 4 + 1] = 11.5;
        let bits = visible_cells(&cells(&depth, 0.0), w, h, &rays, DVec3::ZERO, DVec3::ONE, [4, 4, 4], 0.01);
        assert_eq!(set(&bits), vec![cell(1, 1, 0)]);
        let bits =
            visible_cells(&cells(&[f32::INFINITY; 16], 1.0), w, h, &rays, DVec3::ZERO, DVec3::ONE, [4, 4, 4], 0.01);
        assert!(set(&bits).is_empty());
        // A reach of 1 cell about z = 2.5: the cells from z = 1.5 to 3.5 (k = 1, 2, 3) and, within a
        // quarter cell of the points, none across the x or y faces (the point is at 1.5, 1.5).
        depth[2 * 4 + 1] = 8.5;
        let bits = visible_cells(&cells(&depth, 1.0), w, h, &rays, DVec3::ZERO, DVec3::ONE, [4, 4, 4], 0.01);
        assert_eq!(set(&bits), vec![cell(1, 1, 1), cell(1, 1, 2), cell(1, 1, 3)]);
        // Differing pixels widen: 0 -> 1 -> 4 cells.
        let mut c = cells(&depth, 0.0);
        let (mut a, b) = (vec![0u8; 64], vec![0u8; 64]);
        a[4 * 5 + 2] = 9;
        assert_eq!(widen_where_wrong(&mut c, &a, &b), 1);
        assert_eq!(widen_where_wrong(&mut c, &a, &b), 1);
        assert!(c.reach.iter().enumerate().all(|(i, &r)| r == if i == 5 { 4.0 } else { 0.0 }));
    }

    /// The oracle's frames against the unculled ones: the same image and depth on a dense wavy
    /// field and a sphere, perspective and orthographic, and no more triangles than the implicit
    /// walk draws (it draws whole cells too, and more of them).
    #[test]
    fn oracle_draws_the_unculled_image() {
        use crate::gpu::GpuContext;
        use crate::iso::render::{IsoCulling, IsoOptions, IsoRenderer};
        use crate::iso::MinMaxOctree;
        let Ok(ctx) = GpuContext::new("auto", wgpu::Features::empty()) else { return };
        let mut r = IsoRenderer::new(&ctx);
        let wavy = crate::iso::wavy_field();
        let sphere = crate::iso::sphere_field(24, 0.6);
        let (mut oracle_tris, mut implicit_tris) = (0, 0);
        for vol in [&wavy, &sphere] {
            let tree = MinMaxOctree::build(vol);
            for (eye, cam) in crate::iso::test_views(vol) {
                let mut frame = |culling| {
                    let opts = IsoOptions { culling, ..Default::default() };
                    r.render(&ctx, 64, 56, vol, &tree, 0.0, &cam, &opts).unwrap()
                };
                let (none, implicit, oracle) =
                    (frame(IsoCulling::None), frame(IsoCulling::Implicit), frame(IsoCulling::Oracle));
                assert_eq!(oracle.image, none.image, "{eye:?}");
                assert_eq!(oracle.depth, none.depth, "{eye:?}");
                assert!(oracle.stats.surface_triangles < none.stats.surface_triangles, "{eye:?}");
                oracle_tris += oracle.stats.surface_triangles;
                implicit_tris += implicit.stats.surface_triangles;
            }
        }
        assert!(oracle_tris < implicit_tris, "oracle {oracle_tris} against implicit {implicit_tris}");
    }
}
