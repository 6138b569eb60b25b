// Box test with the hardware's early depth test (box.wgsl is prepended): the same count as
// box_test.wgsl (per tile, the pixels where the front faces of its box are at or in front of the
// depth image, reverse-Z), with the image's depth bound read-only as the depth attachment and
// compared GreaterEqual before the fragment runs (`early_depth_test(force)`: hidden fragments are
// rejected by the rasteriser, block by block, and never reach the atomic). Only where the device
// has SHADER_EARLY_DEPTH_TEST and rasterises reverse-Z depth exactly (not GL: see common.wgsl).

struct Globals {
    view_proj: mat4x4<f32>,
    light_dir: vec4<f32>,
    z_scale: f32,
    _pad0: f32,
    _pad1: f32,
    _pad2: f32,
}

struct DrawArgs {
    index_count: u32,
    instance_count: u32,
    first_index: u32,
    base_vertex: i32,
    first_instance: u32,
}

@group(0) @binding(0) var<uniform> g: Globals;
@group(1) @binding(0) var<storage, read_write> counts: array<atomic<u32>>;
@group(1) @binding(1) var<storage, read> skip: array<DrawArgs>;

struct BoxOut {
    @builtin(position) clip: vec4<f32>,
    @location(0) @interpolate(flat) tile: u32,
}

// One instance per tile: lo.xyz + tile index (bits in w), hi.xyz (render space); tiles whose draw
// is already on are not tested (their box collapses).
@vertex
fn vs_box(@builtin(vertex_index) vi: u32, @location(0) lo: vec4<f32>, @location(1) hi: vec4<f32>) -> BoxOut {
    let tile = bitcast<u32>(lo.w);
    var out: BoxOut;
    out.tile = tile;
    if (skip[tile].instance_count > 0u) {
        out.clip = vec4<f32>(0.0, 0.0, 0.0, 1.0);
        return out;
    }
    out.clip = g.view_proj * vec4<f32>(box_corner(vi, lo.xyz, hi.xyz), 1.0);
    return out;
}

@fragment
@early_depth_test(force)
fn fs_box(v: BoxOut) -> @location(0) u32 {
    atomicAdd(&counts[v.tile], 1u);
    return 0u;
}
