// The scene passes' globals as the box passes read them (prepended by `passes::with_box_wgsl` to
// box_test.wgsl, the slab test, the early box test and occluder_depth.wgsl): the leading fields of
// common.wgsl's `Globals`, bound from the same uniform buffer.

struct Globals {
    view_proj: mat4x4<f32>,
    light_dir: vec4<f32>,
    z_scale: f32,
    // Orthographic: near / (far - near); perspective: -1 (priority_clip).
    ortho_near: f32,
    _pad1: f32,
    _pad2: f32,
}

@group(0) @binding(0) var<uniform> g: Globals;
