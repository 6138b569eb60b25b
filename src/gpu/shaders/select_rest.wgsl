// Second-phase selection: a tile gets its draw when no earlier phase drew it (`done` off) and
// its count is above the threshold; everything else is switched off.

// Params and DrawArgs come from select_common.wgsl (prepended).

@group(0) @binding(0) var<uniform> p: Params;
@group(0) @binding(1) var<storage, read> tile_counts: array<u32>;
@group(0) @binding(2) var<storage, read> src_args: array<DrawArgs>;
@group(0) @binding(3) var<storage, read> done_args: array<DrawArgs>;
@group(0) @binding(4) var<storage, read_write> out_args: array<DrawArgs>;

@compute @workgroup_size(64)
fn select_rest(@builtin(global_invocation_id) gid: vec3<u32>) {
    let i = gid.x + gid.y * (65535u * 64u); // 2-D dispatch beyond 65,535 groups
    if (i >= p.n_tiles) {
        return;
    }
    var a = src_args[i];
    if (done_args[i].instance_count > 0u || f32(tile_counts[i]) <= p.threshold) {
        a.instance_count = 0u;
    }
    out_args[i] = a;
}
