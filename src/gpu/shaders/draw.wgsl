// The lit pass: colour and tile id of the front-most fine surface (common.wgsl is prepended).

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

struct FOutGl {
    @location(0) color: vec4<f32>,
    @location(1) id: u32,
    @builtin(frag_depth) depth: f32,
}

// GL: the same shading as fs_main (kept apart so that fs_main's code is what it always was), with
// frag_depth written (see VOutGl in common.wgsl).
@fragment
fn fs_main_gl(v: VOutGl) -> FOutGl {
    let n0 = cross(dpdx(v.world), dpdy(v.world));
    var n = vec3<f32>(0.0, 0.0, 1.0);
    if (dot(n0, n0) > 0.0) {
        n = normalize(n0);
    }
    let c = objects[tile_object[v.tile]].color.rgb;
    let sun = vec3<f32>(-0.45, 0.45, 0.77);
    let shade = 0.2 + 0.45 * abs(dot(n, g.light_dir.xyz)) + 0.35 * abs(dot(n, sun));
    return FOutGl(vec4<f32>(c * shade, 1.0), v.tile + 1u, gl_depth(v));
}
