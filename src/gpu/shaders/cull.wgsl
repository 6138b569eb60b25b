// Pass 2: exact visible-pixel count per tile from the id buffer (one increment per pixel, so the
// counts of all tiles sum to the covered pixels). Pass 3 (args): tiles above the threshold get
// their fine draw, the others instance_count = 0.

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

struct Params {
    n_tiles: u32,
    // Pixel threshold in prepass pixels (threshold * prepass_scale^2).
    threshold: f32,
    _pad0: u32,
    _pad1: u32,
}

struct DrawArgs {
    index_count: u32,
    instance_count: u32,
    first_index: u32,
    base_vertex: i32,
    first_instance: u32,
}

@group(0) @binding(0) var<uniform> p: Params;
@group(0) @binding(1) var<storage, read> tile_counts: array<u32>;
@group(0) @binding(2) var<storage, read> fine_args: array<DrawArgs>;
@group(0) @binding(3) var<storage, read_write> out_args: array<DrawArgs>;

@compute @workgroup_size(64)
fn build_args(@builtin(global_invocation_id) gid: vec3<u32>) {
    let i = gid.x;
    if (i >= p.n_tiles) {
        return;
    }
    var a = fine_args[i];
    if (f32(tile_counts[i]) <= p.threshold) {
        a.instance_count = 0u;
    }
    out_args[i] = a;
}
