// Occluder depth (globals.wgsl, box.wgsl and priority.wgsl are prepended): a depth image
// that is an earlier image's depth (`fs_copy`, one full-screen triangle) with the front faces of
// boxes drawn over it where they are nearer (`vs_box_depth`), no colour. The boxes are pushed 16
// priority steps farther (2^-17 of their distance): what they occlude must lie clearly behind
// them.

// The earlier image's depth as an unfilterable float texture (as the box test reads it).
@group(1) @binding(0) var source: texture_2d<f32>;

struct DepthOut {
    @builtin(position) clip: vec4<f32>,
    // Clip z and w: the fragment writes z / w (GL's depth range mapping would lose precision).
    @location(0) zw: vec2<f32>,
}

@vertex
fn vs_box_depth(@builtin(vertex_index) vi: u32, @location(0) lo: vec4<f32>, @location(1) hi: vec4<f32>) -> DepthOut {
    var out: DepthOut;
    out.clip = nearer_by(g.view_proj * vec4<f32>(box_corner(vi, lo.xyz, hi.xyz), 1.0), -16.0 * PRIORITY_STEP);
    out.zw = out.clip.zw;
    return out;
}

@fragment
fn fs_box_depth(v: DepthOut) -> @builtin(frag_depth) f32 {
    return v.zw.x / v.zw.y;
}

// One triangle covering the viewport.
@vertex
fn vs_full(@builtin(vertex_index) vi: u32) -> @builtin(position) vec4<f32> {
    let x = f32(vi & 1u) * 4.0 - 1.0;
    let y = f32(vi >> 1u) * 4.0 - 1.0;
    return vec4<f32>(x, y, 0.0, 1.0);
}

@fragment
fn fs_copy(@builtin(position) p: vec4<f32>) -> @builtin(frag_depth) f32 {
    return textureLoad(source, vec2<i32>(floor(p.xy)), 0).r;
}
