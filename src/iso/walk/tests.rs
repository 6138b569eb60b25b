use std::sync::Arc;

use super::*;
use crate::camera::{Camera, Projection};
use crate::gpu::GpuContext;
use crate::iso::render::{IsoCulling, IsoOptions, IsoRenderer, IsoWalk};
use crate::iso::{MinMaxOctree, Volume};

/// Deterministic noise in [-1, 1] (a hash of the index).
fn noise(i: usize, seed: u64) -> f32 {
    let mut x = (i as u64 ^ seed).wrapping_mul(0x9e37_79b9_7f4a_7c15);
    x ^= x >> 29;
    x = x.wrapping_mul(0xbf58_476d_1ce4_e5b9);
    x ^= x >> 32;
    (x as f64 / u64::MAX as f64 * 2.0 - 1.0) as f32
}

/// The host's walk and the compute pass give the same cells seen (per node), the same map to
/// a few ulps (the shader's fused multiply-adds) and the unculled image, on a dense wavy
/// field (contours), smoothed noise with NaN samples and samples on the isovalue, and a
/// sphere; single-cell and coarser occluders, perspective and orthographic views.
#[test]
fn host_walk_matches_the_compute_walk() {
    let Ok(ctx) = GpuContext::new("auto", wgpu::Features::empty()) else { return };
    let mut r = IsoRenderer::new(&ctx);
    let wavy = crate::iso::wavy_field();
    let (nx, ny, nz) = (23, 19, 17);
    let mut v: Vec<f32> = (0..nx * ny * nz).map(|i| noise(i, 7)).collect();
    for _ in 0..2 {
        let at = |i: usize, j: usize, k: usize| v[(k * ny + j) * nx + i];
        let mut s = v.clone();
        for k in 1..nz {
            for j in 1..ny {
                for i in 1..nx {
                    s[(k * ny + j) * nx + i] =
                        (at(i, j, k) + at(i - 1, j, k) + at(i, j - 1, k) + at(i, j, k - 1)) / 4.0;
                }
            }
        }
        v = s;
    }
    for (i, x) in v.iter_mut().enumerate() {
        let h = noise(i, 11);
        if h > 0.97 {
            *x = f32::NAN;
        } else if h < -0.95 {
            *x = 0.0;
        }
    }
    let noisy = Volume::new(Arc::from(v), (nx, ny, nz), [0.0; 3], [1.0; 3]).unwrap();
    let sphere = crate::iso::sphere_field(24, 0.6);
    let mut compared = 0;
    for vol in [&wavy, &noisy, &sphere] {
        let tree = MinMaxOctree::build(vol);
        let md = tree.max_depth();
        for (eye, cam) in crate::iso::test_views(vol) {
            let none_opts = IsoOptions { culling: IsoCulling::None, ..Default::default() };
            let none = r.render(&ctx, 64, 56, vol, &tree, 0.0, &cam, &none_opts).unwrap();
            // (Contours chosen explicitly: by default the host's walk places them on any
            // surface, the compute walk only on dense ones.)
            for (occluder_depth, face_contours) in [(md, false), (md, true), (md - 1, false)] {
                let mut frame = |walk| {
                    let (occluder_depth, face_contours) = (Some(occluder_depth), Some(face_contours));
                    let opts =
                        IsoOptions { occluder_depth, face_contours, walk, return_map: true, ..Default::default() };
                    r.render(&ctx, 64, 56, vol, &tree, 0.0, &cam, &opts).unwrap()
                };
                let (gpu, host) = (frame(IsoWalk::Gpu), frame(IsoWalk::Cpu));
                assert_eq!(gpu.stats.walk_on_host, Some(false));
                assert_eq!(host.stats.walk_on_host, Some(true));
                assert_eq!(host.node_pixels, gpu.node_pixels, "{eye:?} {occluder_depth:?}");
                assert_eq!(host.image, none.image, "{eye:?} {occluder_depth:?}");
                assert_eq!(gpu.image, none.image, "{eye:?} {occluder_depth:?}");
                assert_eq!(host.depth, none.depth);
                for (a, b) in host.map.unwrap().iter().zip(gpu.map.as_ref().unwrap()) {
                    assert!(a == b || (a - b).abs() <= 1e-5 * a.abs(), "map {a} against {b}");
                }
                compared += gpu.node_pixels.iter().filter(|&&n| n > 0).count();
            }
        }
    }
    assert!(compared > 1000, "the walks saw cells to compare ({compared})");
}

/// Jumps of the third skip level (64³ cells) and across boxes of skippable bricks
/// (`skip_reach`; thousands of them in these views) land where the compute walk's steps do:
/// a volume below a plane and above it, with blobs of the other class at a few places and a
/// NaN slab, large enough for whole 64³ bricks (and their rings) of each class.
#[test]
fn huge_jumps_see_what_the_compute_walk_sees() {
    let Ok(ctx) = GpuContext::new("auto", wgpu::Features::empty()) else { return };
    let mut r = IsoRenderer::new(&ctx);
    let blobs = [[70.0, 66.0, 40.0], [20.0, 100.0, 100.0], [130.5, 64.0, 66.5], [64.0, 20.0, 90.0]];
    let mut vol = Volume::from_fn((150, 140, 136), [0.0; 3], [1.0; 3], |x, y, z| {
        let bump: f64 =
            blobs.iter().map(|b| (-((x - b[0]).powi(2) + (y - b[1]).powi(2) + (z - b[2]).powi(2)) / 8.0).exp()).sum();
        let base = if z > 66.5 { 1.0 } else { -1.0 };
        (base * (1.0 - 2.5 * bump)) as f32
    })
    .unwrap();
    let mut v = vol.values.to_vec();
    for k in 100..110 {
        for j in 0..40 {
            for i in 0..150 {
                v[(k * 140 + j) * 150 + i] = f32::NAN;
            }
        }
    }
    vol = Volume::new(Arc::from(v), (150, 140, 136), [0.0; 3], [1.0; 3]).unwrap();
    let tree = MinMaxOctree::build(&vol);
    let md = tree.max_depth();
    let dims = tree.dims_at_depth(md).unwrap();
    let mut nodes = tree.leaf_nodes(0.0).unwrap();
    crate::iso::bricks::dilate_nan(&mut nodes, dims);
    let (huge, _) = crate::iso::bricks::pack_nodes(&nodes, dims, true).2.unwrap();
    for k in [1, 2] {
        assert!(huge.contains(&k), "whole 64³ bricks of class {k}");
    }
    let c = [75.0, 70.0, 68.0];
    for (eye, proj) in [
        ([300.0, 210.0, 190.0], Projection::Perspective),
        ([-120.0, 40.0, -60.0], Projection::Perspective),
        ([75.5, 70.0, 400.0], Projection::Orthographic),
    ] {
        let cam = Camera::look_at(eye, c, [0.0, 0.0, 1.0], 40.0, None, None, proj, Some(200.0), 1.0).unwrap();
        let none_opts = IsoOptions { culling: IsoCulling::None, ..Default::default() };
        let none = r.render(&ctx, 64, 56, &vol, &tree, 0.0, &cam, &none_opts).unwrap();
        let mut frame = |walk| {
            let opts = IsoOptions { walk, return_map: true, face_contours: Some(true), ..Default::default() };
            r.render(&ctx, 64, 56, &vol, &tree, 0.0, &cam, &opts).unwrap()
        };
        let (gpu, host) = (frame(IsoWalk::Gpu), frame(IsoWalk::Cpu));
        assert_eq!(host.node_pixels, gpu.node_pixels, "{eye:?}");
        assert_eq!(host.image, none.image, "{eye:?}");
        assert_eq!(gpu.image, none.image, "{eye:?}");
        for (a, b) in host.map.unwrap().iter().zip(gpu.map.as_ref().unwrap()) {
            assert!(a == b || (a - b).abs() <= 1e-5 * a.abs(), "map {a} against {b}");
        }
        assert!(host.stats.surface_triangles < none.stats.surface_triangles, "{eye:?}");
    }
}

/// The walk's counts on a scene whose answer is known: a horizontal plane between sample
/// layers 2 and 3 of 8, seen straight down and orthographically over the middle of the box (6 × 4
/// of its 7 × 7 cells), so that every pixel's ray enters the box; cell by cell (no skipping) each takes the 4 cells
/// above the surface, the one holding it and the one below, where its face proves the crossing
/// (6 steps). Jumping skippable bricks takes fewer; the GPU's walk counts nothing.
#[test]
fn walk_counts_on_a_plane_seen_from_above() {
    let Ok(ctx) = GpuContext::new("auto", wgpu::Features::empty()) else { return };
    let mut r = IsoRenderer::new(&ctx);
    let vol = Volume::from_fn((8, 8, 8), [0.0; 3], [1.0; 3], |_, _, z| (z - 2.5) as f32).unwrap();
    let tree = MinMaxOctree::build(&vol);
    let cam = Camera::look_at(
        [3.5, 3.5, 50.0],
        [3.5, 3.5, 0.0],
        [0.0, 1.0, 0.0],
        40.0,
        None,
        None,
        Projection::Orthographic,
        Some(4.0),
        1.0,
    )
    .unwrap();
    let (w, h) = (24, 16);
    let frame = |r: &mut IsoRenderer, walk, space_skipping| {
        let opts = IsoOptions { walk, space_skipping, ..Default::default() };
        r.render(&ctx, w, h, &vol, &tree, 0.0, &cam, &opts).unwrap().stats
    };
    let cells = frame(&mut r, IsoWalk::Cpu, false);
    assert_eq!(cells.walk_rays, u64::from(w * h));
    assert_eq!(cells.walk_steps, 6 * u64::from(w * h));
    let skipping = frame(&mut r, IsoWalk::Cpu, true);
    assert_eq!(skipping.walk_rays, u64::from(w * h));
    assert!(skipping.walk_steps <= cells.walk_steps, "{} steps", skipping.walk_steps);
    let gpu = frame(&mut r, IsoWalk::Gpu, false);
    assert_eq!((gpu.walk_rays, gpu.walk_steps), (0, 0));
    let none = r
        .render(&ctx, w, h, &vol, &tree, 0.0, &cam, &IsoOptions { culling: IsoCulling::None, ..Default::default() })
        .unwrap()
        .stats;
    assert_eq!((none.walk_rays, none.walk_steps), (0, 0));
}

/// `contour_side` on faces whose answer is known: uniform faces, a corner cut off, a segment
/// across, a corner on the isovalue, and a point too near the segment for the margin.
#[test]
fn contour_side_known_faces() {
    let straight = [0.0, 0.0, 1.0];
    assert_eq!(contour_side([-1.0; 4], [0.5, 0.5], straight, 0.01), 1);
    assert_eq!(contour_side([1.0; 4], [0.3, 0.9], straight, 0.01), 2);
    // Corner (0, 0) above, cut off at u = v = 0.5: inside its triangle above, beyond it below.
    let f = [1.0, -1.0, -1.0, -1.0];
    assert_eq!(contour_side(f, [0.1, 0.1], straight, 0.01), 2);
    assert_eq!(contour_side(f, [0.8, 0.8], straight, 0.01), 1);
    assert_eq!(contour_side(f, [0.2, 0.2], straight, 0.01), 2);
    assert_eq!(contour_side(f, [0.251, 0.251], straight, 0.01), 0, "within the margin of the segment");
    // Two corners on each side: the segment from (0.25, 0) to (0.75, 1).
    let f = [1.0, -3.0, 3.0, -1.0];
    assert_eq!(contour_side(f, [0.1, 0.5], straight, 0.01), 2);
    assert_eq!(contour_side(f, [0.9, 0.5], straight, 0.01), 1);
    // A corner on the isovalue: not known.
    assert_eq!(contour_side([0.0, 1.0, 1.0, 1.0], [0.9, 0.9], straight, 0.01), 0);
    // Ambiguous face (opposite corners alike): its middle is not known.
    assert_eq!(contour_side([1.0, -1.0, -1.0, 1.0], [0.5, 0.5], straight, 0.01), 0);
}
