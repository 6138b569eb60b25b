// Shared by the box passes (prepended to box_test.wgsl and to the isosurface's iso.wgsl): the 12
// triangles of an axis-aligned box, wound counter-clockwise seen from outside. Corner c has
// x = bit 0, y = bit 1, z = bit 2 (0 = lo, 1 = hi).
var<private> CUBE: array<u32, 36> = array<u32, 36>(
    0u, 4u, 6u, 0u, 6u, 2u,  // -x
    1u, 3u, 7u, 1u, 7u, 5u,  // +x
    0u, 1u, 5u, 0u, 5u, 4u,  // -y
    2u, 6u, 7u, 2u, 7u, 3u,  // +y
    0u, 2u, 3u, 0u, 3u, 1u,  // -z
    4u, 5u, 7u, 4u, 7u, 6u,  // +z
);

// Corner of box lo..hi for vertex `vi` (0..36) of its triangle list.
fn box_corner(vi: u32, lo: vec3<f32>, hi: vec3<f32>) -> vec3<f32> {
    return corner(CUBE[vi], lo, hi);
}

// Corner `c` (0..8) of box lo..hi (indexed draws: `CUBE` as the index buffer).
fn corner(c: u32, lo: vec3<f32>, hi: vec3<f32>) -> vec3<f32> {
    return select(lo, hi, vec3<bool>((c & 1u) != 0u, (c & 2u) != 0u, (c & 4u) != 0u));
}
