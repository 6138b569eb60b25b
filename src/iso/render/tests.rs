use super::*;
use crate::camera::Projection;

/// The sphere fields' view: from (3, 1, 1) towards the origin, 40 degrees.
fn camera() -> Camera {
    let persp = Projection::Perspective;
    Camera::look_at([3.0, 1.0, 1.0], [0.0; 3], [0.0, 0.0, 1.0], 40.0, None, None, persp, None, 1.0).unwrap()
}

fn device() -> Option<GpuContext> {
    GpuContext::new("auto", wgpu::Features::empty()).ok()
}

#[test]
fn sphere_implicit_equals_none() {
    let Some(ctx) = device() else { return };
    let mut r = IsoRenderer::new(&ctx);
    let vol = super::super::sphere_field(24, 0.6);
    let tree = MinMaxOctree::build(&vol);
    let cam = camera();
    let none = r
        .render(&ctx, 64, 64, &vol, &tree, 0.0, &cam, &IsoOptions { culling: IsoCulling::None, ..Default::default() })
        .unwrap();
    let md = tree.max_depth();
    let imp = r
        .render(
            &ctx,
            64,
            64,
            &vol,
            &tree,
            0.0,
            &cam,
            &IsoOptions { occluder_depth: Some(md), cull_depth: Some(md - 1), ..Default::default() },
        )
        .unwrap();
    assert_eq!(none.image, imp.image);
    assert!(imp.stats.surface_triangles < none.stats.surface_triangles);
    assert!(imp.stats.nodes_visible < imp.stats.nodes_straddling);
}

#[test]
fn lazy_volume_draws_the_resident_image_reading_only_visible_nodes() {
    use crate::iso::store::{BrickCache, Resident};
    let Some(ctx) = device() else { return };
    let vol = super::super::sphere_field(97, 0.6);
    let dims = [vol.nx, vol.ny, vol.nz];
    let store = BrickCache::new(Box::new(Resident { values: vol.values.clone(), dims }), dims, 8 << 20);
    let lazy =
        crate::iso::Volume::lazy(std::sync::Arc::new(store), 0.0, (97, 97, 97), vol.origin, vol.spacing).unwrap();
    let (tree, ltree) = (MinMaxOctree::build(&vol), MinMaxOctree::try_build(&lazy).unwrap());
    let built = lazy.bytes_read();
    let cam = camera();
    let sd = tree.stored_depth();
    let opts = IsoOptions { occluder_depth: Some(sd), cull_depth: Some(sd), ..Default::default() };
    let mut r = IsoRenderer::new(&ctx);
    let want = r.render(&ctx, 64, 64, &vol, &tree, 0.0, &cam, &opts).unwrap();
    assert_eq!(want.stats.bytes_read, 0);
    let mut r = IsoRenderer::new(&ctx);
    let got = r.render(&ctx, 64, 64, &lazy, &ltree, 0.0, &cam, &IsoOptions::default()).unwrap();
    assert_eq!((got.stats.occluder_depth, got.stats.cull_depth), (sd, sd), "a lazy volume's defaults");
    assert_eq!(got.image, want.image);
    assert_eq!(got.stats.bytes_read, lazy.bytes_read() - built);
    // (Bricks of 32³: the near half of the sphere touches most of the 27 bricks of this small cube.)
    assert!(got.stats.bytes_read > 0 && got.stats.bytes_read < 4 * 97 * 97 * 97, "{}", got.stats.bytes_read);
    let again = r.render(&ctx, 64, 64, &lazy, &ltree, 0.0, &cam, &IsoOptions::default()).unwrap();
    assert_eq!((again.image, again.stats.bytes_read), (want.image, 0), "patches and bricks cached");
}
