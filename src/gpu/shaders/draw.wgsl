// The lit pass: colour and tile id of the front-most fine surface (common.wgsl is prepended).
// Its vertex entry points are vs_main / vs_gl's transform, word for word (so that depths agree
// with the prepass), plus the vertex's scalar for colour by data.

// Colour maps of this frame's objects: 256 rows each, then the object's NaN colour.
@group(0) @binding(3) var<storage, read> lut: array<vec4<f32>>;

struct VOutDraw {
    @builtin(position) @invariant clip: vec4<f32>,
    @location(0) world: vec3<f32>,
    @location(1) @interpolate(flat) tile: u32,
    // The colouring scalar: the vertex's value (mode 1) or its object-relative z (mode 2).
    @location(2) s: f32,
}

@vertex
fn vs_draw(@location(0) pos: vec3<f32>, @location(1) value: f32, @builtin(instance_index) tile: u32) -> VOutDraw {
    let o = objects[tile_object[tile]];
    let p = (pos + o.offset.xyz) * vec3<f32>(1.0, 1.0, g.z_scale);
    var out: VOutDraw;
    out.clip = g.view_proj * vec4<f32>(p, 1.0);
    out.world = p;
    out.tile = tile;
    out.s = select(value, pos.z, o.cmap.z > 1.5);
    return out;
}

// The object's colour at scalar s: flat, or matplotlib's mapping of a 256-row colour map
// (row floor(256 t), t = (s - lo) / (hi - lo) clamped to [0, 1], the last row at t = 1); scalars
// below -1e37 are no data (geometry.rs NO_DATA) and get the NaN colour.
fn base_color(o: Object, s: f32) -> vec3<f32> {
    if (o.cmap.z < 0.5) {
        return o.color.rgb;
    }
    let base = u32(o.cmap.w);
    if (s < -1e37) {
        return lut[base + 256u].rgb;
    }
    let t = clamp((s - o.cmap.x) * o.cmap.y, 0.0, 1.0);
    return lut[base + min(u32(t * 256.0), 255u)].rgb;
}

struct FOut {
    @location(0) color: vec4<f32>,
    // Tile index + 1 of the visible surface (0 = nothing).
    @location(1) id: u32,
}

@fragment
fn fs_main(v: VOutDraw) -> FOut {
    // Flat normal from screen-space derivatives: no per-vertex normals to store.
    let n0 = cross(dpdx(v.world), dpdy(v.world));
    var n = vec3<f32>(0.0, 0.0, 1.0);
    if (dot(n0, n0) > 0.0) {
        n = normalize(n0);
    }
    let o = objects[tile_object[v.tile]];
    let c = base_color(o, v.s);
    // Two-sided Lambert: a head light (so nothing facing the viewer is dark) plus a fixed sun from
    // the north-west at 50° elevation (so gentle undulations of a horizon read as relief).
    let sun = vec3<f32>(-0.45, 0.45, 0.77);
    let shade = 0.2 + 0.45 * abs(dot(n, g.light_dir.xyz)) + 0.35 * abs(dot(n, sun));
    var out: FOut;
    // Translucent objects (volume lenses, drawn blended) are unlit, with the object's opacity.
    out.color = vec4<f32>(c * select(shade, 1.0, o.color.a < 1.0), o.color.a);
    out.id = v.tile + 1u;
    return out;
}

// GL: vs_draw's transform with clip z and w carried to the fragment (see VOutGl in common.wgsl).
struct VOutDrawGl {
    @builtin(position) @invariant clip: vec4<f32>,
    @location(0) world: vec3<f32>,
    @location(1) @interpolate(flat) tile: u32,
    @location(2) zw: vec2<f32>,
    @location(3) s: f32,
}

@vertex
fn vs_draw_gl(@location(0) pos: vec3<f32>, @location(1) value: f32, @builtin(instance_index) tile: u32) -> VOutDrawGl {
    let o = objects[tile_object[tile]];
    let p = (pos + o.offset.xyz) * vec3<f32>(1.0, 1.0, g.z_scale);
    let clip = g.view_proj * vec4<f32>(p, 1.0);
    return VOutDrawGl(clip, p, tile, clip.zw, select(value, pos.z, o.cmap.z > 1.5));
}

struct FOutGl {
    @location(0) color: vec4<f32>,
    @location(1) id: u32,
    @builtin(frag_depth) depth: f32,
}

// GL: the same shading as fs_main (kept apart so that fs_main's code is what it always was), with
// frag_depth written (see VOutGl in common.wgsl).
@fragment
fn fs_main_gl(v: VOutDrawGl) -> FOutGl {
    let n0 = cross(dpdx(v.world), dpdy(v.world));
    var n = vec3<f32>(0.0, 0.0, 1.0);
    if (dot(n0, n0) > 0.0) {
        n = normalize(n0);
    }
    let o = objects[tile_object[v.tile]];
    let c = base_color(o, v.s);
    let sun = vec3<f32>(-0.45, 0.45, 0.77);
    let shade = 0.2 + 0.45 * abs(dot(n, g.light_dir.xyz)) + 0.35 * abs(dot(n, sun));
    return FOutGl(vec4<f32>(c * select(shade, 1.0, o.color.a < 1.0), o.color.a), v.tile + 1u, v.zw.x / v.zw.y);
}
