// Box test (globals.wgsl, box.wgsl and priority.wgsl are prepended): per tile, the pixels
// where the front faces of its box are at or in front of a depth image (reverse-Z: nearer =
// larger). The comparison is done here by hand, with no depth attachment, so hidden fragments are
// never counted and no early-depth-test feature is needed. Tiles whose draw is already on
// (`skip`), or whose `gate` count is 0, are not tested: their box collapses.

struct DrawArgs {
    index_count: u32,
    instance_count: u32,
    first_index: u32,
    base_vertex: i32,
    first_instance: u32,
}

// The depth image as an unfilterable float texture (GLSL cannot textureLoad depth textures).
@group(1) @binding(0) var depth: texture_2d<f32>;
@group(1) @binding(1) var<storage, read_write> counts: array<atomic<u32>>;
@group(1) @binding(2) var<storage, read> skip: array<DrawArgs>;
// Per tile: its boxes are tested only when this is above 0 (the count of an earlier box pass).
@group(1) @binding(3) var<storage, read> gate: array<u32>;

// Clip position `clip` at the largest depth-tie priority (15: 11 steps past a horizon's; common.wgsl
// `priority_clip`): boxes and slabs at least as near as anything drawn at their place, whatever
// its object's priority.
fn nearest(clip: vec4<f32>) -> vec4<f32> {
    return nearer_by(clip, 11.0 * PRIORITY_STEP);
}

// How far `grown` moves an occludee's faces out, in pixels' worth of world units at each vertex:
// more than the rasteriser's snapping of vertices can move a surface's edge against the edge of
// the occludee standing on it (8 sub-pixel bits, as the GPUs and CPU rasterisers we know of
// have: each vertex within 1/362 px, so two edges within 1/181 px of each other), at the cost of
// counting pixels that far outside the occludee.
const DILATE_PX: f32 = 1.0 / 128.0;

// The clip position of vertex `p` (render space) of a convex occludee (a box, a slab's prism)
// moved by `grow` times DILATE_PX pixels' worth of world units at its depth. `grow` moves every
// face out by at least that much (a box: the corner's signs; a prism: its corner's miter across
// the walls, and along z as far as its sloping top and bottom need: slab_test.wgsl), so the
// occludee grows by a ball that covers DILATE_PX pixels on screen: a pixel whose centre the
// surface inside covers by less than the rasteriser's snapping stays covered by the occludee
// too, where a box's face or a slab's wall stands on the surface's own edge. Vertices behind the
// eye stay put.
fn grown(p: vec3<f32>, grow: vec3<f32>) -> vec4<f32> {
    let clip = g.view_proj * vec4<f32>(p, 1.0);
    if (clip.w <= 0.0) {
        return clip;
    }
    let t = DILATE_PX * clip.w * g.pixel_world.x;
    return clip + g.view_proj * vec4<f32>(grow * t, 0.0);
}

struct BoxOut {
    @builtin(position) clip: vec4<f32>,
    @location(0) @interpolate(flat) tile: u32,
    // Clip z and w: GL's depth range mapping loses reverse-Z precision in `clip.z`, so the GL
    // entry point compares z / w (common.wgsl does the same for the scene passes).
    @location(1) zw: vec2<f32>,
}

// One instance per tile: lo.xyz + tile index (bits in w), hi.xyz (render space).
@vertex
fn vs_box(@builtin(vertex_index) vi: u32, @location(0) lo: vec4<f32>, @location(1) hi: vec4<f32>) -> BoxOut {
    let tile = bitcast<u32>(lo.w);
    var out: BoxOut;
    out.tile = tile;
    if (skip[tile].instance_count > 0u || gate[tile] == 0u) {
        out.clip = vec4<f32>(0.0, 0.0, 0.0, 1.0); // all corners equal: nothing rasterised
        out.zw = vec2<f32>(0.0, 1.0);
        return out;
    }
    // The draw is indexed by `CUBE`: `vi` is the corner.
    let grow = select(vec3<f32>(-1.0), vec3<f32>(1.0), vec3<bool>((vi & 1u) != 0u, (vi & 2u) != 0u, (vi & 4u) != 0u));
    out.clip = nearest(grown(corner(vi, lo.xyz, hi.xyz), grow));
    out.zw = out.clip.zw;
    return out;
}

// The render pass's one attachment (the id image) has its writes masked off.
@fragment
fn fs_box(v: BoxOut) -> @location(0) u32 {
    let d = textureLoad(depth, vec2<i32>(floor(v.clip.xy)), 0).r;
    if (v.clip.z >= d) {
        atomicAdd(&counts[v.tile], 1u);
    }
    return 0u;
}

// GL: the same test with the fragment's depth as z / w.
@fragment
fn fs_box_gl(v: BoxOut) -> @location(0) u32 {
    let d = textureLoad(depth, vec2<i32>(floor(v.clip.xy)), 0).r;
    if (v.zw.x / v.zw.y >= d) {
        atomicAdd(&counts[v.tile], 1u);
    }
    return 0u;
}
