// The scene passes' per-frame uniforms (gpu::layout::Globals), group 0, binding 0: prepended to
// common.wgsl for the scene passes and by `passes::with_box_wgsl` for the box passes (box_test.wgsl,
// the slab test, the early box test and occluder_depth.wgsl), which bind the same buffer.

struct Globals {
    view_proj: mat4x4<f32>,
    // Direction towards the head light (over the viewer's shoulder), render space, w unused.
    light_dir: vec4<f32>,
    z_scale: f32,
    // Orthographic: near / (far - near); perspective: -1 (priority_clip).
    ortho_near: f32,
    // x: the world size of one of the frame's pixels at clip w = 1 (the box tests' `grown`); y unused.
    pixel_world: vec2<f32>,
    // The pixel rays (draw.wgsl `fine_depth`): perspective, the eye in render space and w = 1;
    // orthographic, the unit view direction and w = 0.
    eye: vec4<f32>,
}

@group(0) @binding(0) var<uniform> g: Globals;
