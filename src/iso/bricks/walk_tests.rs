use super::*;
use crate::camera::{Camera, Projection};
use crate::gpu::GpuContext;
use crate::iso::render::{IsoCulling, IsoOptions, IsoRenderer, IsoWalk};
use crate::iso::Volume;

/// The compute walk and the host's.
const WALKS: [IsoWalk; 2] = [IsoWalk::Gpu, IsoWalk::Cpu];

/// Large uniform regions (Below under a plane, Above over it, a NaN slab) with small blobs of
/// the other class centred on brick corners, edges and faces of both skip levels.
fn bricky_volume() -> Volume {
    let blobs: Vec<[f64; 3]> = vec![
        [16.0, 16.0, 16.0],
        [32.0, 20.0, 12.0],
        [4.0, 30.5, 8.0],
        [48.0, 48.0, 36.0],
        [20.0, 8.0, 40.0],
        [36.5, 44.0, 44.0],
        [12.0, 52.0, 24.5],
        // Its cells reach x = 44, y = 44: a fine brick's ring but not the brick.
        [45.5, 45.5, 40.0],
    ];
    Volume::from_fn((66, 58, 50), [0.0; 3], [1.0; 3], move |x, y, z| {
        if (56.0..60.0).contains(&x) && z < 30.0 {
            return f32::NAN;
        }
        let base = if z > 32.5 { 1.0 } else { -1.0 };
        let bump: f64 =
            blobs.iter().map(|b| (-((x - b[0]).powi(2) + (y - b[1]).powi(2) + (z - b[2]).powi(2)) / 2.0).exp()).sum();
        (base * (1.0 - 2.5 * bump)) as f32
    })
    .unwrap()
}

#[test]
fn skipping_changes_nothing_drawn() {
    let Ok(ctx) = GpuContext::new("auto", wgpu::Features::empty()) else { return };
    let mut r = IsoRenderer::new(&ctx);
    let vol = bricky_volume();
    let tree = crate::iso::MinMaxOctree::build(&vol);
    let md = tree.max_depth();
    let cls = node_classes(&tree, 0.0, md);
    let [(f, _), (c, _)]: [_; 2] =
        brick_classes(&cls, tree.dims_at_depth(md).unwrap(), &[FINE_SHIFT, COARSE_SHIFT]).try_into().unwrap();
    for (k, v) in [(CLASS_BELOW, &f), (CLASS_ABOVE, &f), (CLASS_BELOW, &c), (CLASS_ABOVE, &c)] {
        assert!(v.contains(&k), "the volume has skippable bricks of class {k} at both levels");
    }
    let (c, up, p, o) = ([32.5, 28.5, 24.5], [0.0, 1.0, 0.3], Projection::Perspective, Projection::Orthographic);
    let views = [
        ([140.0, 90.0, 80.0], c, up, p),
        ([-60.0, 20.0, -40.0], c, up, p),
        ([32.0, 28.5, 160.0], c, up, p),
        ([200.0, 16.0, 16.0], c, up, o),
        ([-80.0, 150.0, 90.0], c, up, o),
        // One unit per pixel, pixel centres on integers: every ray runs along cell edges.
        ([32.5, 28.5, 200.0], c, [0.0, 1.0, 0.0], o),
        ([-120.0, 28.5, 20.5], [32.5, 28.5, 20.5], [0.0, 0.0, 1.0], o),
        // Four units per pixel, pixel centres 0.005 short of multiples of 4: rays run inside
        // brick faces, cells beyond them are seen only through the walk's rounding margin.
        ([29.995, 25.995, 200.0], [29.995, 25.995, 24.5], [0.0, 1.0, 0.0], o),
    ];
    let mut proven = 0;
    for (eye, target, up, proj) in views {
        let h = if eye[0] == 29.995 { 320.0 } else { 80.0 };
        let cam = Camera::look_at(eye, target, up, 45.0, None, None, proj, Some(h), 1.0).unwrap();
        let mut frame = |culling, space_skipping, cull_depth, walk| {
            let opts = IsoOptions { culling, space_skipping, cull_depth, walk, return_map: true, ..Default::default() };
            r.render(&ctx, 96, 80, &vol, &tree, 0.0, &cam, &opts).unwrap()
        };
        // Both walks: the compute pass and the host's.
        for (cull_depth, w) in [None, Some(md), Some(md - 3)].into_iter().flat_map(|d| WALKS.map(|w| (d, w))) {
            let none = frame(IsoCulling::None, true, cull_depth, w);
            let walk = frame(IsoCulling::Implicit, false, cull_depth, w);
            let skip = frame(IsoCulling::Implicit, true, cull_depth, w);
            assert_eq!(skip.map, walk.map, "{eye:?} {proj:?} {cull_depth:?}");
            assert_eq!(skip.stats.surface_triangles, walk.stats.surface_triangles);
            assert_eq!(skip.image, walk.image);
            assert_eq!(skip.image, none.image, "{eye:?} {proj:?} {cull_depth:?}");
            assert_eq!(skip.depth, none.depth);
            assert!(skip.stats.surface_triangles <= none.stats.surface_triangles);
            proven += skip.map.as_ref().unwrap().iter().any(|v| v.is_finite()) as u32;
        }
    }
    assert!(proven >= 24, "the map proves something in most frames ({proven})");
}

/// The walk that reads the corners of every face it crosses (and stops right behind the
/// surface) draws the unculled image with fewer triangles than the one that knows only
/// uniform faces. The views include rays that graze faces whose contour they pass within a
/// hundredth of a cell of (the margin is measured across space, not within the face): the
/// top view's rays run almost parallel to the x faces through the plane z = 32.5.
#[test]
fn face_contours_change_nothing_drawn() {
    let Ok(ctx) = GpuContext::new("auto", wgpu::Features::empty()) else { return };
    let mut r = IsoRenderer::new(&ctx);
    let wavy = Volume::from_fn((41, 37, 33), [0.0; 3], [1.0, 1.0, 0.5], |x, y, z| {
        ((0.37 * x).sin() + (0.29 * y + 0.11 * x).cos() + (0.61 * z).sin() * 0.8 - 0.2) as f32
    })
    .unwrap();
    let (c, up, p) = ([20.0, 18.0, 8.0], [0.0, 0.0, 1.0], Projection::Perspective);
    let wavy_views =
        [([90.0, 60.0, 40.0], c, up, p), ([-40.0, 10.0, -20.0], c, up, p), ([20.5, 18.0, 90.0], c, [0.0, 1.0, 0.0], p)];
    let bricky = bricky_volume();
    let bricky_views = [
        ([32.0, 28.5, 160.0], [32.5, 28.5, 24.5], [0.0, 1.0, 0.3], p),
        ([140.0, 90.0, 80.0], [32.5, 28.5, 24.5], [0.0, 1.0, 0.3], p),
    ];
    let (mut with, mut without) = (0, 0);
    for (vol, views) in [(&wavy, &wavy_views[..]), (&bricky, &bricky_views[..])] {
        let tree = crate::iso::MinMaxOctree::build(vol);
        for &(eye, target, up, proj) in views {
            let cam = Camera::look_at(eye, target, up, 45.0, None, None, proj, None, 1.0).unwrap();
            for walk in WALKS {
                let mut frame = |culling, contours| {
                    let opts = IsoOptions { culling, face_contours: Some(contours), walk, ..Default::default() };
                    r.render(&ctx, 96, 80, vol, &tree, 0.0, &cam, &opts).unwrap()
                };
                let none = frame(IsoCulling::None, true);
                let faces = frame(IsoCulling::Implicit, true);
                let uniform = frame(IsoCulling::Implicit, false);
                assert_eq!(faces.image, none.image, "{eye:?}");
                assert_eq!(faces.depth, none.depth, "{eye:?}");
                assert_eq!(uniform.image, none.image, "{eye:?}");
                assert!(faces.stats.surface_triangles <= uniform.stats.surface_triangles, "{eye:?}");
                let bricks = tree.straddling_at_depth(0.0, tree.max_depth() - CONTOUR_SHIFT);
                let words = tree.contour_bricks(&bricks).0.len();
                assert_eq!(faces.stats.contour_bytes, 4 * words as u64);
                with += faces.stats.surface_triangles;
                without += uniform.stats.surface_triangles;
            }
        }
    }
    assert!(with * 10 < without * 9, "contours draw at least 10 % fewer triangles ({with} vs {without})");
}
