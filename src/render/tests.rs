//! GPU tests on scenes whose answer is known by construction (run on lavapipe without a GPU).

use super::*;
use crate::camera::Projection;
use crate::cull::{CullOptions, Stat};
use crate::error::Interrupt;
use crate::gpu::BACKGROUND;
use crate::scene::{AddOptions, GridFrame};

fn opts(cf: f64) -> AddOptions {
    AddOptions { color: Some([0.5, 0.5, 0.5]), ..AddOptions::new(cf) }
}

fn plane(s: &mut Scene, z: f64, n: usize, size: f64, tiles: usize, cf: f64) -> u32 {
    let zz = vec![z; n * n];
    let d = size / (n - 1) as f64;
    s.add_heightfield(&zz, n, n, GridFrame::new([-size / 2.0, -size / 2.0], [d, d]), (tiles, tiles), None, opts(cf))
        .unwrap()
}

fn top_down(h: f64) -> Camera {
    Camera::look_at(
        [0.0, 0.0, h],
        [0.0, 0.0, 0.0],
        [0.0, 1.0, 0.0],
        90.0,
        None,
        None,
        Projection::Perspective,
        None,
        1.0,
    )
    .unwrap()
}

#[test]
fn plane_from_above_covers_and_has_exact_depth() {
    let mut s = Scene::new();
    // A 100 x 100 plane at z = 0 seen from 100 m with a 90° fov: it spans exactly the middle half.
    plane(&mut s, 0.0, 11, 100.0, 2, 1.0);
    let mut r = Renderer::new(64, 64, "auto").unwrap();
    let out = r.render(&s, &top_down(100.0), &RenderOptions::default()).unwrap();
    let covered: Vec<usize> = (0..64 * 64).filter(|&i| out.depth[i].is_finite()).collect();
    assert_eq!(covered.len(), 32 * 32);
    for &i in &covered {
        let (x, y) = (i % 64, i / 64);
        assert!((16..48).contains(&x) && (16..48).contains(&y));
        assert!((out.depth[i] - 100.0).abs() < 1e-3 * 100.0, "{}", out.depth[i]);
    }
    // Visible pixels per tile: four quadrants of 16 x 16.
    assert_eq!(out.tile_pixels, vec![256; 4]);
    assert!(out.image.chunks(4).enumerate().all(|(i, px)| out.depth[i].is_finite() != (px == BACKGROUND)));
}

#[test]
fn three_pass_counts_sum_to_coverage_and_hidden_plane_is_culled() {
    let mut s = Scene::new();
    plane(&mut s, 0.0, 21, 100.0, 4, 1.0);
    let lower = plane(&mut s, -10.0, 21, 60.0, 3, 1.0);
    let mut r = Renderer::new(80, 60, "auto").unwrap();
    let cam = Camera::look_at(
        [30.0, -120.0, 90.0],
        [0.0, 0.0, 0.0],
        [0.0, 0.0, 1.0],
        40.0,
        None,
        None,
        Projection::Perspective,
        None,
        1.0,
    )
    .unwrap();
    let none = r.render(&s, &cam, &RenderOptions::default()).unwrap();
    let three_pass = |conservative| RenderOptions {
        culling: "three_pass".into(),
        cull: CullOptions {
            pixel_threshold: 0.0,
            conservative,
            prepass_scale: CullOptions::default_prepass_scale(conservative),
            ..Default::default()
        },
        ..Default::default()
    };
    let tp = r.render(&s, &cam, &three_pass(false)).unwrap();
    let covered = none.depth.iter().filter(|d| d.is_finite()).count() as u32;
    assert!(covered > 0);
    assert_eq!(tp.tile_pixels.iter().sum::<u32>(), covered);
    assert_eq!(tp.tile_pixels, none.tile_pixels);
    // The lower plane's 9 tiles are wholly hidden under the upper one.
    let first_lower = 16;
    assert!(s.object(lower).unwrap().tiles.len() == 9);
    assert!(tp.tile_pixels[first_lower..].iter().all(|&c| c == 0));
    assert!(tp.tile_drawn[first_lower..].iter().all(|&d| !d));
    assert_eq!(tp.image, none.image);
    assert!(tp.stats.triangles_drawn < none.stats.triangles_drawn);
    // Conservative: the box test finds nothing more to draw (the lower boxes lie behind).
    let cons = r.render(&s, &cam, &three_pass(true)).unwrap();
    assert_eq!(cons.tile_drawn, tp.tile_drawn);
    assert_eq!(cons.stats.get("tiles_drawn_second"), Some(Stat::Count(0)));
    assert_eq!(cons.image, none.image);
}

/// An interrupt that fires on its `n`-th poll (1 = the first), counting polls in `calls`.
fn nth_poll(n: usize) -> (Interrupt, std::sync::Arc<std::sync::atomic::AtomicUsize>) {
    use std::sync::atomic::{AtomicUsize, Ordering};
    let calls = std::sync::Arc::new(AtomicUsize::new(0));
    let c = calls.clone();
    (Interrupt::new(move || c.fetch_add(1, Ordering::Relaxed) + 1 >= n), calls)
}

/// An interrupt stops a frame at a stage boundary with `Error::Interrupted`, for every strategy and
/// every stage it is polled at; the next frame of the same renderer equals the first one.
#[test]
fn interrupted_frames_leave_the_renderer_usable() {
    let mut s = Scene::new();
    plane(&mut s, 0.0, 21, 100.0, 4, 1.0);
    plane(&mut s, -10.0, 21, 60.0, 3, 1.0);
    let cam = top_down(120.0);
    let mut r = Renderer::new(48, 40, "auto").unwrap();
    for name in crate::cull::names() {
        let want = r.render(&s, &cam, &RenderOptions::culling(name)).unwrap();
        // Polls without a GPU wait slice: after upload, after the strategy (a fast frame may end
        // before any wait slice times out, so later polls are not guaranteed to happen).
        for n in 1..=2 {
            let (interrupt, calls) = nth_poll(n);
            let e = r.render(&s, &cam, &RenderOptions { interrupt, ..RenderOptions::culling(name) }).unwrap_err();
            assert!(matches!(e, Error::Interrupted), "{name}, poll {n}: {e}");
            assert_eq!(calls.load(std::sync::atomic::Ordering::Relaxed), n, "{name}");
            let again = r.render(&s, &cam, &RenderOptions::culling(name)).unwrap();
            assert_eq!(
                (again.image, again.depth, again.tile_pixels),
                (want.image.clone(), want.depth.clone(), want.tile_pixels.clone()),
                "{name}"
            );
        }
        // A hook that never fires changes nothing.
        let (interrupt, _) = nth_poll(usize::MAX);
        let same = r.render(&s, &cam, &RenderOptions { interrupt, ..RenderOptions::culling(name) }).unwrap();
        assert_eq!(same.image, want.image, "{name}");
    }
}

/// An interrupted build returns `Error::Interrupted` and leaves the scene as it was (no object,
/// no origin): the same add afterwards gives the scene a fresh one gets.
#[test]
fn interrupted_builds_leave_the_scene_unchanged() {
    let n = 200;
    let z: Vec<f64> = (0..n * n).map(|k| ((k % n) as f64 * 0.1).sin() + (k / n) as f64 * 0.01).collect();
    let add = |s: &mut Scene, interrupt: Interrupt| {
        s.add_heightfield(
            &z,
            n,
            n,
            GridFrame::new([10.0, 20.0], [1.0, 1.0]),
            (8, 8),
            None,
            AddOptions { interrupt, ..opts(4.0) },
        )
    };
    let mut s = Scene::new();
    let e = add(&mut s, Interrupt::new(|| true)).unwrap_err();
    assert!(matches!(e, Error::Interrupted), "{e}");
    assert!(s.objects().is_empty() && s.n_tiles() == 0);
    let mesh = s.add_mesh(
        &[[0.0; 3], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]],
        &[[0, 1, 2]],
        "m",
        None,
        AddOptions { interrupt: Interrupt::new(|| true), ..opts(1.0) },
    );
    assert!(matches!(mesh, Err(Error::Interrupted)) && s.objects().is_empty());
    let mut fresh = Scene::new();
    add(&mut s, Interrupt::default()).unwrap();
    add(&mut fresh, Interrupt::new(|| false)).unwrap();
    assert_eq!(s.origin(), fresh.origin());
    assert_eq!(s.objects()[0].tiles[5].positions, fresh.objects()[0].tiles[5].positions);
}

/// An interrupt while the GPU draws a large frame (over `LONG_FRAME_TRIANGLES`, so on GL the
/// submission runs on the worker thread): the call returns Interrupted (unless the GPU was faster
/// than the first poll slice), and the next frame waits for the abandoned work and equals the first.
#[test]
fn interrupt_during_the_gpu_wait_of_a_large_frame() {
    let mut s = Scene::new();
    let n = 1100; // 2.4 M triangles
    let z: Vec<f64> = (0..n * n).map(|k| ((k % n) as f64 * 0.05).sin() * ((k / n) as f64 * 0.04).cos()).collect();
    s.add_heightfield(&z, n, n, GridFrame::new([0.0, 0.0], [1.0, 1.0]), (8, 8), None, opts(4.0)).unwrap();
    let cam = Camera::look_at(
        [-50.0, -50.0, 300.0],
        [550.0, 550.0, 0.0],
        [0.0, 0.0, 1.0],
        50.0,
        None,
        None,
        Projection::Perspective,
        None,
        1.0,
    )
    .unwrap();
    let mut r = Renderer::new(64, 48, "auto").unwrap();
    let want = r.render(&s, &cam, &RenderOptions::default()).unwrap();
    for _ in 0..2 {
        // Polls 1 and 2 are the stage checks; 3 is the first wait slice.
        let (interrupt, _) = nth_poll(3);
        match r.render(&s, &cam, &RenderOptions { interrupt, ..Default::default() }) {
            Err(Error::Interrupted) | Ok(_) => {}
            Err(e) => panic!("{e}"),
        }
    }
    let again = r.render(&s, &cam, &RenderOptions::default()).unwrap();
    assert_eq!((again.image, again.depth), (want.image, want.depth));
}
