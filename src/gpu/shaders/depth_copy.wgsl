// Depth read-back through a shader: copies a band of rows of a depth texture into a storage
// buffer, one f32 per texel, row-major without padding. Used instead of a depth-texture-to-buffer
// copy, which GL (llvmpipe, GLES) lacks (downlevel flag DEPTH_TEXTURE_AND_BUFFER_COPIES).

struct Band {
    // First texture row of this band; `out[0]` is texel (0, y0).
    y0: u32,
    // Rows in this band.
    rows: u32,
    _pad0: u32,
    _pad1: u32,
}

// A depth texture bound as unfilterable float (WebGPU allows it for depth formats): naga's GLSL
// backend cannot `textureLoad` a `texture_depth_2d`, but can a `texture_2d<f32>` (texelFetch).
@group(0) @binding(0) var depth: texture_2d<f32>;
@group(0) @binding(1) var<storage, read_write> out: array<f32>;
@group(0) @binding(2) var<uniform> band: Band;

@compute @workgroup_size(16, 16)
fn copy_depth(@builtin(global_invocation_id) gid: vec3<u32>) {
    let dims = textureDimensions(depth);
    if (gid.x >= dims.x || gid.y >= band.rows) {
        return;
    }
    let y = band.y0 + gid.y;
    out[gid.y * dims.x + gid.x] = textureLoad(depth, vec2<i32>(i32(gid.x), i32(y)), 0).r;
}
