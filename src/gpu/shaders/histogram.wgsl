// Exact visible-pixel count per tile from an id image: one increment per pixel, so the counts
// of all tiles sum to the covered pixels.

@group(0) @binding(0) var ids: texture_2d<u32>;
@group(0) @binding(1) var<storage, read_write> counts: array<atomic<u32>>;

// Pixels per invocation, along a row.
const RUN: u32 = 16u;

// One invocation per RUN pixels of a row (x from RUN * gid.x, row gid.y): neighbouring pixels
// mostly share a tile, so it adds each run of one id once, which cuts atomic traffic by up to
// RUN times. No workgroup memory nor barrier: a CPU rasteriser runs a barrier's workgroup as
// coroutines switched at the barrier (lavapipe, a 1280 x 1024 image of one tile: 16 x 16
// workgroups sharing their ids through workgroup memory took some 25 ms, these 4 to 11).
@compute @workgroup_size(8, 8)
fn histogram(@builtin(global_invocation_id) gid: vec3<u32>) {
    let dims = textureDimensions(ids);
    let x0 = gid.x * RUN;
    if (gid.y >= dims.y || x0 >= dims.x) {
        return;
    }
    var run = 0u;
    var n = 0u;
    for (var i = 0u; i < RUN && x0 + i < dims.x; i = i + 1u) {
        let id = textureLoad(ids, vec2<i32>(i32(x0 + i), i32(gid.y)), 0).r;
        if (id != run) {
            if (run != 0u) {
                atomicAdd(&counts[run - 1u], n);
            }
            run = id;
            n = 0u;
        }
        n = n + 1u;
    }
    if (run != 0u) {
        atomicAdd(&counts[run - 1u], n);
    }
}
