use super::*;
use crate::camera::Projection;

fn device() -> Option<GpuContext> {
    GpuContext::new("auto", wgpu::Features::empty()).ok()
}

#[test]
fn sphere_implicit_equals_none() {
    let Some(ctx) = device() else { return };
    let mut r = IsoRenderer::new(&ctx);
    let vol = super::super::sphere_field(24, 0.6);
    let tree = MinMaxOctree::build(&vol);
    let cam = Camera::look_at(
        [3.0, 1.0, 1.0],
        [0.0; 3],
        [0.0, 0.0, 1.0],
        40.0,
        None,
        None,
        Projection::Perspective,
        None,
        1.0,
    )
    .unwrap();
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
