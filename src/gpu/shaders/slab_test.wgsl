// Slab test (gpu/slab_test.rs): box_test.wgsl's count with a height-field tile's slab
// (lod/slab.rs: closed prisms, wound outwards, that hold the tile's surface) in place of its
// boxes. Per tile, the pixels where the slab's front faces are at or in front of a depth image
// (reverse-Z: nearer = larger), compared by hand as box_test.wgsl does. Tiles whose draw is already on (`skip`), or whose `gate` count is 0, are not tested.

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
@group(1) @binding(0) var depth: texture_2d<f32>;
@group(1) @binding(1) var<storage, read_write> counts: array<atomic<u32>>;
@group(1) @binding(2) var<storage, read> skip: array<DrawArgs>;
@group(1) @binding(3) var<storage, read> gate: array<u32>;
// Per tile: its object's placement in render space before exaggeration (xyz, as the lit pass's
// `offset`), and how far its slab grows along z, up on the top surface and down on the bottom
// one (w: the drawn level's error and a margin against round-off, world units).
@group(1) @binding(4) var<storage, read> place: array<vec4<f32>>;

struct SlabOut {
    @builtin(position) clip: vec4<f32>,
    @location(0) @interpolate(flat) tile: u32,
    @location(1) zw: vec2<f32>,
}

// A slab vertex: origin-relative x, y, z and its side (+1 top, -1 bottom); the instance is the
// tile (each slab is drawn as one instance whose first_instance is its tile).
@vertex
fn vs_slab(@location(0) v: vec4<f32>, @builtin(instance_index) tile: u32) -> SlabOut {
    var out: SlabOut;
    out.tile = tile;
    if (skip[tile].instance_count > 0u || gate[tile] == 0u) {
        out.clip = vec4<f32>(0.0, 0.0, 0.0, 1.0); // all corners equal: nothing rasterised
        out.zw = vec2<f32>(0.0, 1.0);
        return out;
    }
    let p = place[tile];
    let pos = vec3<f32>(v.xy, v.z + v.w * p.w);
    out.clip = g.view_proj * vec4<f32>((pos + p.xyz) * vec3<f32>(1.0, 1.0, g.z_scale), 1.0);
    out.zw = out.clip.zw;
    return out;
}

@fragment
fn fs_slab(v: SlabOut) -> @location(0) u32 {
    let d = textureLoad(depth, vec2<i32>(floor(v.clip.xy)), 0).r;
    if (v.clip.z >= d) {
        atomicAdd(&counts[v.tile], 1u);
    }
    return 0u;
}

// GL: the same test with the fragment's depth as z / w (see box_test.wgsl).
@fragment
fn fs_slab_gl(v: SlabOut) -> @location(0) u32 {
    let d = textureLoad(depth, vec2<i32>(floor(v.clip.xy)), 0).r;
    if (v.zw.x / v.zw.y >= d) {
        atomicAdd(&counts[v.tile], 1u);
    }
    return 0u;
}
