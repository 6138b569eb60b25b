// Exact visible-pixel count per tile from an id image: one increment per pixel, so the counts
// of all tiles sum to the covered pixels.

@group(0) @binding(0) var ids: texture_2d<u32>;
@group(0) @binding(1) var<storage, read_write> counts: array<atomic<u32>>;

var<workgroup> run_id: array<u32, 256>;

@compute @workgroup_size(16, 16)
fn histogram(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(local_invocation_index) li: u32) {
    let dims = textureDimensions(ids);
    var id = 0u;
    if (gid.x < dims.x && gid.y < dims.y) {
        id = textureLoad(ids, vec2<i32>(gid.xy), 0).r;
    }
    // Neighbouring pixels mostly share a tile: let only the first lane of each run along x add
    // the run's length, which cuts atomic traffic by up to 16x.
    run_id[li] = id;
    workgroupBarrier();
    let x = li % 16u;
    if (id == 0u || (x > 0u && run_id[li - 1u] == id)) {
        return;
    }
    var n = 1u;
    while (x + n < 16u && run_id[li + n] == id) {
        n = n + 1u;
    }
    atomicAdd(&counts[id - 1u], n);
}
