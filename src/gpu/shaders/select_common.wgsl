// Shared by the selection passes (prepended to select.wgsl and select_rest.wgsl).

struct Params {
    n_tiles: u32,
    // Counts at most this switch the draw off (in the counted image's pixels).
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
