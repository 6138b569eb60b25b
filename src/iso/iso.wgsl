// Implicit occluders (Pesco et al.): the occlusion map marched per pixel through the occluder
// depth's class grid, exact per-node visible-pixel counts against it, and the lit isosurface.
// Depth is reverse-Z everywhere (1 = near, 0 = far): "nearer" means a larger depth value.

struct Globals {
    view_proj: mat4x4<f32>,
    // Direction towards the light (render space), w unused.
    light_dir: vec4<f32>,
    color: vec4<f32>,
}

@group(0) @binding(0) var<uniform> g: Globals;

// CUBE and box_corner come from gpu/shaders/box.wgsl (prepended).

struct BoxOut {
    // Invariant: the test pass rasterises identical depths for identical boxes.
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

// ---- The occlusion map: one invocation per pixel walks its ray through the grid of nodes at the
// occluder depth (3-D DDA, near to far) and stops at the first node of one class (Below / Above)
// met after a node of the other class with no NaN node in between; the map is the depth of that
// node's entry point, pushed farther by `lo.w` (render units). 0 (= far, nothing proven) where no
// such pair exists. Classes: 2 bits per node, 16 per word: 0 = may hold surface (passable),
// 1 = Below, 2 = Above, 3 = has a NaN sample (outside the domain: resets the walk).
struct MapParams {
    inv_view_proj: mat4x4<f32>,
    // xyz: the volume's box (render space); lo.w: the margin, hi.w unused.
    lo: vec4<f32>,
    hi: vec4<f32>,
    // xyz: a node's size (render space); the last node per axis may end earlier, at `hi`.
    node: vec4<f32>,
    // xyz: nodes per axis; w: image width.
    dims: vec4<u32>,
    // x: image height.
    size: vec4<u32>,
}

@group(1) @binding(0) var<uniform> mp: MapParams;
@group(1) @binding(1) var<storage, read> classes: array<u32>;
@group(1) @binding(2) var<storage, read_write> map_out: array<f32>;

fn node_class(c: vec3<i32>) -> u32 {
    let u = vec3<u32>(c);
    let i = (u.z * mp.dims.y + u.y) * mp.dims.x + u.x;
    return (classes[i >> 4u] >> ((i & 15u) * 2u)) & 3u;
}

fn unproject(ndc: vec3<f32>) -> vec3<f32> {
    let p = mp.inv_view_proj * vec4<f32>(ndc, 1.0);
    return p.xyz / p.w;
}

@compute @workgroup_size(8, 8)
fn cs_map(@builtin(global_invocation_id) gid: vec3<u32>) {
    let w = mp.dims.w;
    let h = mp.size.x;
    if (gid.x >= w || gid.y >= h) {
        return;
    }
    let ndc = vec2<f32>((f32(gid.x) + 0.5) / f32(w) * 2.0 - 1.0, 1.0 - (f32(gid.y) + 0.5) / f32(h) * 2.0);
    // From the near plane along the pixel's ray (t = 0 at the near plane).
    let o = unproject(vec3<f32>(ndc, 1.0));
    var d = unproject(vec3<f32>(ndc, 0.5)) - o;
    d = select(d, vec3<f32>(1e-30), abs(d) < vec3<f32>(1e-30));
    let inv = 1.0 / d;
    let ta = (mp.lo.xyz - o) * inv;
    let tb = (mp.hi.xyz - o) * inv;
    let tmin = min(ta, tb);
    let tmax = max(ta, tb);
    let t0 = max(max(tmin.x, tmin.y), max(tmin.z, 0.0));
    let t1 = min(min(tmax.x, tmax.y), tmax.z);
    var result = 0.0;
    if (t0 < t1) {
        let dims = vec3<i32>(mp.dims.xyz);
        let p = o + d * t0;
        var c = vec3<i32>(clamp(floor((p - mp.lo.xyz) / mp.node.xyz), vec3<f32>(0.0), vec3<f32>(dims - 1)));
        let stp = select(vec3<i32>(-1), vec3<i32>(1), d > vec3<f32>(0.0));
        let ahead = select(vec3<f32>(0.0), vec3<f32>(1.0), d > vec3<f32>(0.0));
        var tnext = (mp.lo.xyz + (vec3<f32>(c) + ahead) * mp.node.xyz - o) * inv;
        let tdelta = abs(mp.node.xyz * inv);
        var last = 0u;
        var t_enter = t0;
        loop {
            let k = node_class(c);
            if (k == 3u) {
                last = 0u;
            } else if (k != 0u) {
                if (last != 0u && last != k) {
                    let q = o + d * (t_enter + mp.lo.w / length(d));
                    let clip = g.view_proj * vec4<f32>(q, 1.0);
                    result = clamp(clip.z / clip.w, 0.0, 1.0);
                    break;
                }
                last = k;
            }
            let tm = min(min(tnext.x, tnext.y), tnext.z);
            if (tm >= t1) {
                break;
            }
            t_enter = tm;
            // One axis at a time: a ray through an edge or corner visits the nodes beside it too.
            if (tnext.x <= tm) {
                c.x += stp.x;
                tnext.x += tdelta.x;
            } else if (tnext.y <= tm) {
                c.y += stp.y;
                tnext.y += tdelta.y;
            } else {
                c.z += stp.z;
                tnext.z += tdelta.z;
            }
            if (any(c < vec3<i32>(0)) || any(c >= dims)) {
                break;
            }
        }
    }
    map_out[gid.y * w + gid.x] = result;
}

// Node test: count the pixels where the node box's front face is nearer than (or as near as) the
// occlusion map. The comparison is done here, by hand, so no early-depth-test feature is needed
// and hidden fragments are never counted.
@group(1) @binding(0) var<storage, read> map_depth: array<f32>;
@group(1) @binding(1) var<storage, read_write> counts: array<atomic<u32>>;
// The map pass's parameters (for the image width).
@group(1) @binding(2) var<uniform> tp: MapParams;

fn map_at(xy: vec2<f32>) -> f32 {
    let p = vec2<u32>(floor(xy));
    return map_depth[p.y * tp.dims.w + p.x];
}

@fragment
fn fs_test(v: BoxOut) -> @location(0) u32 {
    if (v.clip.z >= map_at(v.clip.xy)) {
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
fn fs_test_gl(v: BoxOutGl) -> @location(0) u32 {
    if (v.zw.x / v.zw.y >= map_at(v.clip.xy)) {
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
