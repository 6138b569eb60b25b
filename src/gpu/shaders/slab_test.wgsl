// Slab test (gpu/slab_test.rs): box_test.wgsl's count (it is prepended, with box.wgsl: its
// globals, bindings, `BoxOut` and fragment entry points fs_box / fs_box_gl, and fs_box_early
// where that is appended) with a height-field tile's slab (lod/slab.rs: closed prisms, wound
// outwards, that hold the tile's surface) in place of its boxes: per tile, the pixels where the
// slab's front faces are at or in front of the depth image. Tiles whose draw is already on, or
// whose gate count is 0, are not drawn (slab_gate.wgsl switched their draws off).

// Per tile: its object's placement in render space before exaggeration (xyz, as the lit pass's
// `offset`), and how far its slab grows along z, up on the top surface and down on the bottom
// one (w: the drawn level's error and a margin against round-off, world units). 8192 tiles to a
// row (gpu::slab_test::PLACE_ROW).
@group(1) @binding(4) var place: texture_2d<f32>;

// A slab vertex: origin-relative x, y, z, then its corner's miter across its prism's walls over
// 4 (x, y), the steepest slope of its prism's top and bottom over 8 (z) and its side (+1 top,
// -1 bottom); the instance is the tile (each slab is drawn as one instance whose first_instance
// is its tile).
@vertex
fn vs_slab(@location(0) v: vec3<f32>, @location(1) o: vec4<f32>, @builtin(instance_index) tile: u32) -> BoxOut {
    var out: BoxOut;
    out.tile = tile;
    let p = textureLoad(place, vec2<u32>(tile % 8192u, tile / 8192u), 0);
    let side = sign(o.w);
    let pos = vec3<f32>(v.xy, v.z + side * p.w);
    let render = (pos + p.xyz) * vec3<f32>(1.0, 1.0, g.z_scale);
    // Moved by the miter, a top (bottom) sloping by `s` (render space) comes out along its normal
    // by the vertical move over sqrt(1 + s^2), less the miter's climb up the slope. Capped at 64
    // (half a pixel's worth of height): only tops steeper than about 88 degrees then come out by
    // less than the snapping margin, and a steep exaggerated top never grows tall on screen.
    let miter = 4.0 * o.xy;
    let s = 8.0 * o.z * g.z_scale;
    let up = min(sqrt(1.0 + s * s) + length(miter) * s, 64.0);
    out.clip = nearest(grown(render, vec3<f32>(miter, side * up)));
    out.zw = out.clip.zw;
    return out;
}
