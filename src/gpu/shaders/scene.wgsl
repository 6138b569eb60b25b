// Scene geometry: one vertex buffer (f32 positions relative to the scene origin), drawn with
// multi-draw-indirect where first_instance carries the global tile index.

struct Globals {
    view_proj: mat4x4<f32>,
    // Direction towards the head light (over the viewer's shoulder), render space, w unused.
    light_dir: vec4<f32>,
    z_scale: f32,
    _pad0: f32,
    _pad1: f32,
    _pad2: f32,
}

struct Object {
    // Translation (world units) applied before exaggeration.
    offset: vec4<f32>,
    color: vec4<f32>,
}

@group(0) @binding(0) var<uniform> g: Globals;
@group(0) @binding(1) var<storage, read> objects: array<Object>;
@group(0) @binding(2) var<storage, read> tile_object: array<u32>;

struct VOut {
    // Invariant so that the depth prepass and later passes rasterise identical depth.
    @builtin(position) @invariant clip: vec4<f32>,
    @location(0) world: vec3<f32>,
    @location(1) @interpolate(flat) tile: u32,
}

@vertex
fn vs_main(@location(0) pos: vec3<f32>, @builtin(instance_index) tile: u32) -> VOut {
    let o = objects[tile_object[tile]];
    let p = (pos + o.offset.xyz) * vec3<f32>(1.0, 1.0, g.z_scale);
    var out: VOut;
    out.clip = g.view_proj * vec4<f32>(p, 1.0);
    out.world = p;
    out.tile = tile;
    return out;
}

struct FOut {
    @location(0) color: vec4<f32>,
    // Tile index + 1 of the visible surface (0 = nothing).
    @location(1) id: u32,
}

@fragment
fn fs_main(v: VOut) -> FOut {
    // Flat normal from screen-space derivatives: no per-vertex normals to store.
    let n0 = cross(dpdx(v.world), dpdy(v.world));
    var n = vec3<f32>(0.0, 0.0, 1.0);
    if (dot(n0, n0) > 0.0) {
        n = normalize(n0);
    }
    let c = objects[tile_object[v.tile]].color.rgb;
    // Two-sided Lambert: a head light (so nothing facing the viewer is dark) plus a fixed sun from
    // the north-west at 50° elevation (so gentle undulations of a horizon read as relief).
    let sun = vec3<f32>(-0.45, 0.45, 0.77);
    let shade = 0.2 + 0.45 * abs(dot(n, g.light_dir.xyz)) + 0.35 * abs(dot(n, sun));
    var out: FOut;
    out.color = vec4<f32>(c * shade, 1.0);
    out.id = v.tile + 1u;
    return out;
}

// Depth prepass: only the tile id (for the exact per-tile visible-pixel histogram).
@fragment
fn fs_id(v: VOut) -> @location(0) u32 {
    return v.tile + 1u;
}
