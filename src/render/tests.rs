//! GPU tests on scenes whose answer is known by construction (run on lavapipe without a GPU).

use super::*;
use crate::camera::Projection;
use crate::cull::Stat;
use crate::gpu::BACKGROUND;
use crate::scene::{AddOptions, GridFrame};

fn opts(cf: f64) -> AddOptions {
    AddOptions { coarse_factor: cf, name: None, color: Some([0.5, 0.5, 0.5]) }
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
        cull: CullOptions { pixel_threshold: 0.0, conservative, ..Default::default() },
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
