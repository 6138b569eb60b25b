// Slab gate: the slab test's draws (one per slab, its tile in first_instance) switched off where
// the tile's draw is already on (`done_args`) or its gate count (the pixels of its gate at or in
// front of the image: its slab's gate or its whole box; every gate open for the gates' own draws)
// is 0, so the slab test's vertex stage never runs for the slabs of tiles whose gate is hidden.
// The test's count is the same as drawing every slab with the gate checked in its vertex stage;
// only the work differs.

// Params (n_tiles: here the number of slab draws) and DrawArgs come from select_common.wgsl.

@group(0) @binding(0) var<uniform> p: Params;
@group(0) @binding(1) var<storage, read> gate_counts: array<u32>;
@group(0) @binding(2) var<storage, read> src_args: array<DrawArgs>;
@group(0) @binding(3) var<storage, read> done_args: array<DrawArgs>;
@group(0) @binding(4) var<storage, read_write> out_args: array<DrawArgs>;

@compute @workgroup_size(64)
fn slab_gate(@builtin(global_invocation_id) gid: vec3<u32>) {
    let k = gid.x + gid.y * (65535u * 64u); // 2-D dispatch beyond 65,535 groups
    if (k >= p.n_tiles) {
        return;
    }
    var a = src_args[k];
    let tile = a.first_instance;
    if (done_args[tile].instance_count > 0u || gate_counts[tile] == 0u) {
        a.instance_count = 0u;
    }
    out_args[k] = a;
}
