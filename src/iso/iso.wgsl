// Implicit occluders (Pesco et al.): occlusion map from octree boxes, exact per-node visible-pixel
// counts against it, and the lit isosurface. Depth is reverse-Z everywhere (1 = near, 0 = far):
// "nearer" means a larger depth value.

struct Globals {
    view_proj: mat4x4<f32>,
    // Direction towards the light (render space), w unused.
    light_dir: vec4<f32>,
    color: vec4<f32>,
}

@group(0) @binding(0) var<uniform> g: Globals;

// CUBE and box_corner come from gpu/shaders/box.wgsl (prepended).

struct BoxOut {
    // Invariant: the map passes and the test pass rasterise identical depths for identical boxes.
    @builtin(position) @invariant clip: vec4<f32>,
    @location(0) @interpolate(flat) id: u32,
}

// One instance per box: lo.xyz + id (bit pattern in w), hi.xyz.
@vertex
fn vs_box(@builtin(vertex_index) vi: u32, @location(0) lo: vec4<f32>, @location(1) hi: vec4<f32>) -> BoxOut {
    var out: BoxOut;
    out.clip = g.view_proj * vec4<f32>(box_corner(vi, lo.xyz, hi.xyz), 1.0);
    out.id = bitcast<u32>(lo.w);
    return out;
}

// Pass 3 of the map: keep only fragments strictly farther than the reference depth (the nearest
// point of the boxes of the other class on this pixel's ray); the depth test (Greater) then keeps
// the nearest of them. Depth textures are bound as unfilterable float (`texture_2d<f32>`, `.r`):
// naga's GLSL backend cannot `textureLoad` a `texture_depth_2d`.
@group(1) @binding(0) var ref_depth: texture_2d<f32>;

@fragment
fn fs_beyond(v: BoxOut) {
    let r = textureLoad(ref_depth, vec2<i32>(floor(v.clip.xy)), 0).r;
    if (v.clip.z >= r) {
        discard;
    }
}

// Node test: count the pixels where the node box's front face is nearer than (or as near as) the
// occlusion map. The comparison is done here, by hand, so no early-depth-test feature is needed
// and hidden fragments are never counted.
@group(1) @binding(0) var map_depth: texture_2d<f32>;
@group(1) @binding(1) var<storage, read_write> counts: array<atomic<u32>>;

@fragment
fn fs_test(v: BoxOut) -> @location(0) u32 {
    let m = textureLoad(map_depth, vec2<i32>(floor(v.clip.xy)), 0).r;
    if (v.clip.z >= m) {
        atomicAdd(&counts[v.id], 1u);
        return v.id + 1u;
    }
    return 0u;
}

// The isosurface: positions relative to the volume centre (render space), smooth normals.
struct SurfOut {
    @builtin(position) clip: vec4<f32>,
    @location(0) normal: vec3<f32>,
}

@vertex
fn vs_surf(@location(0) pos: vec3<f32>, @location(1) normal: vec3<f32>) -> SurfOut {
    var out: SurfOut;
    out.clip = g.view_proj * vec4<f32>(pos, 1.0);
    out.normal = normal;
    return out;
}

@fragment
fn fs_surf(v: SurfOut) -> @location(0) vec4<f32> {
    var n = vec3<f32>(0.0, 0.0, 1.0);
    if (dot(v.normal, v.normal) > 0.0) {
        n = normalize(v.normal);
    }
    // Two-sided Lambert with an ambient term.
    let shade = 0.3 + 0.7 * abs(dot(n, g.light_dir.xyz));
    return vec4<f32>(g.color.rgb * shade, 1.0);
}

// ---- The GL variant (`*_gl` entry points, chosen by IsoPasses::new on the GL backend): clip z and
// w go to the fragment, which uses z / w as its depth (compared by hand and written as frag_depth)
// instead of GL's own depth, which keeps only ~2^-24 absolute precision of reverse-Z depth (see
// gpu/shaders/common.wgsl). The bodies repeat those above rather than sharing helpers, so that the
// other backends' entry points compile exactly as before (a shared shading helper measurably
// slowed lavapipe's lit pass).

struct BoxOutGl {
    @builtin(position) @invariant clip: vec4<f32>,
    @location(0) @interpolate(flat) id: u32,
    @location(1) zw: vec2<f32>,
}

@vertex
fn vs_box_gl(@builtin(vertex_index) vi: u32, @location(0) lo: vec4<f32>, @location(1) hi: vec4<f32>) -> BoxOutGl {
    let c = CUBE[vi];
    let sel = vec3<bool>((c & 1u) != 0u, (c & 2u) != 0u, (c & 4u) != 0u);
    let clip = g.view_proj * vec4<f32>(select(lo.xyz, hi.xyz, sel), 1.0);
    return BoxOutGl(clip, bitcast<u32>(lo.w), clip.zw);
}

@fragment
fn fs_near_gl(v: BoxOutGl) -> @builtin(frag_depth) f32 {
    return v.zw.x / v.zw.y;
}

@fragment
fn fs_beyond_gl(v: BoxOutGl) -> @builtin(frag_depth) f32 {
    let z = v.zw.x / v.zw.y;
    if (z >= textureLoad(ref_depth, vec2<i32>(floor(v.clip.xy)), 0).r) {
        discard;
    }
    return z;
}

@fragment
fn fs_test_gl(v: BoxOutGl) -> @location(0) u32 {
    if (v.zw.x / v.zw.y >= textureLoad(map_depth, vec2<i32>(floor(v.clip.xy)), 0).r) {
        atomicAdd(&counts[v.id], 1u);
        return v.id + 1u;
    }
    return 0u;
}

struct SurfOutGl {
    @builtin(position) clip: vec4<f32>,
    @location(0) normal: vec3<f32>,
    @location(1) zw: vec2<f32>,
}

@vertex
fn vs_surf_gl(@location(0) pos: vec3<f32>, @location(1) normal: vec3<f32>) -> SurfOutGl {
    let clip = g.view_proj * vec4<f32>(pos, 1.0);
    return SurfOutGl(clip, normal, clip.zw);
}

struct SurfFragGl {
    @location(0) color: vec4<f32>,
    @builtin(frag_depth) depth: f32,
}

@fragment
fn fs_surf_gl(v: SurfOutGl) -> SurfFragGl {
    var n = vec3<f32>(0.0, 0.0, 1.0);
    if (dot(v.normal, v.normal) > 0.0) {
        n = normalize(v.normal);
    }
    let shade = 0.3 + 0.7 * abs(dot(n, g.light_dir.xyz));
    return SurfFragGl(vec4<f32>(g.color.rgb * shade, 1.0), v.zw.x / v.zw.y);
}
