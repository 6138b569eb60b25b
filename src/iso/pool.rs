//! The isosurface's patches kept on the GPU between frames: one vertex and one index buffer of
//! the volume's render space ([`Space`]) to which every cached patch is appended the first time
//! it is drawn. A frame then uploads nothing for the patches already there: `culling = none` draws
//! their triangles straight from the pool (runs of consecutive patches, one draw each), implicit
//! culling uploads only the indices of the cells it keeps.
//!
//! Contract:
//! - A patch is known by its allocation (`Arc` address), checked with a `Weak` to it that the slot
//!   keeps, so an address is never reused while its slot lives. Patches of the renderer's cache
//!   live as long as the cache keeps them; a patch the cache dropped leaves a dead slot.
//! - When dead slots hold more than half of the pool's triangles, or the render space changes
//!   (z exaggeration, volume), the pool starts again from the patches of the frame: its size stays
//!   within about twice the cached patches' own.
//! - Vertices are `[x, y, z, nx, ny, nz]` f32 in render space (normals divided by the exaggeration
//!   in z), indices are global (a patch's first vertex added), as `draw_surface` builds them.

use super::march::SurfacePatch;
use super::passes::{
    check_surface_size, fill_parts, index_buffer, offset_triangles, pack_vertices, submit_surface, triangle_counts,
    IsoPasses, Space, Targets, TRIANGLE_BYTES, VERTEX_BYTES,
};
use crate::error::Result;
use crate::gpu::GpuContext;
use std::collections::HashMap;
use std::sync::{Arc, Weak};

struct Slot {
    patch: Weak<SurfacePatch>,
    /// First vertex and first triangle in the pool.
    vbase: u32,
    tbase: u32,
}

#[derive(Default)]
pub(super) struct SurfacePool {
    /// The render space of the pool's vertices: origin and z_scale bits.
    space: Option<[u64; 4]>,
    vertices: Option<wgpu::Buffer>,
    indices: Option<wgpu::Buffer>,
    /// Vertices and triangles appended so far.
    nv: u64,
    nt: u64,
    slots: HashMap<usize, Slot>,
}

fn space_key(s: &Space) -> [u64; 4] {
    [s.origin.x.to_bits(), s.origin.y.to_bits(), s.origin.z.to_bits(), s.z_scale.to_bits()]
}

fn address(p: &Arc<SurfacePatch>) -> usize {
    Arc::as_ptr(p) as usize
}

impl SurfacePool {
    /// Bytes of the pool's GPU buffers.
    pub(super) fn bytes(&self) -> u64 {
        self.vertices.as_ref().map_or(0, |b| b.size()) + self.indices.as_ref().map_or(0, |b| b.size())
    }

    pub(super) fn clear(&mut self) {
        *self = Self::default();
    }

    /// Forgets the slots of patches the cache dropped; their triangles stay in the buffers until
    /// the live ones hold less than half of them, when the pool is emptied (buffers freed) and
    /// starts again.
    pub(super) fn trim(&mut self) {
        self.slots.retain(|_, s| s.patch.strong_count() > 0);
        let live_t: u64 = self.slots.values().filter_map(|s| s.patch.upgrade()).map(|p| p.triangles.len() as u64).sum();
        if 2 * live_t < self.nt || self.slots.is_empty() {
            let space = self.space;
            self.clear();
            self.space = space;
        }
    }

    /// The vertex and index buffers (None while empty).
    pub(super) fn buffers(&self) -> Option<(&wgpu::Buffer, &wgpu::Buffer)> {
        self.vertices.as_ref().zip(self.indices.as_ref())
    }

    /// Puts every patch of `patches` in the pool (for `space`), appending those not there yet
    /// (copies of the old buffers recorded into `enc`, new data written through the queue, both
    /// ahead of what `enc` records next). Returns each patch's (first vertex, first triangle).
    pub(super) fn ensure(
        &mut self,
        ctx: &GpuContext,
        enc: &mut wgpu::CommandEncoder,
        patches: &[Arc<SurfacePatch>],
        space: &Space,
    ) -> Result<Vec<(u32, u32)>> {
        if self.space != Some(space_key(space)) {
            self.clear();
            self.space = Some(space_key(space));
        }
        self.trim();
        let mut seen = std::collections::HashSet::new();
        let fresh: Vec<&Arc<SurfacePatch>> =
            patches.iter().filter(|p| !self.slots.contains_key(&address(p)) && seen.insert(address(p))).collect();
        if !fresh.is_empty() {
            self.append(ctx, enc, &fresh, space)?;
        }
        Ok(patches
            .iter()
            .map(|p| {
                let s = &self.slots[&address(p)];
                (s.vbase, s.tbase)
            })
            .collect())
    }

    fn append(
        &mut self,
        ctx: &GpuContext,
        enc: &mut wgpu::CommandEncoder,
        fresh: &[&Arc<SurfacePatch>],
        space: &Space,
    ) -> Result<()> {
        let d = &ctx.device;
        let vlens: Vec<usize> = fresh.iter().map(|p| p.positions.len()).collect();
        let tlens: Vec<usize> = fresh.iter().map(|p| p.triangles.len()).collect();
        let (nv, nt) = (self.nv + vlens.iter().sum::<usize>() as u64, self.nt + tlens.iter().sum::<usize>() as u64);
        check_surface_size(ctx, nv, nt)?;
        let max = ctx.limits.max_buffer_size;
        // Grow to at least 1.5 x what is needed (amortised appends), within the limit.
        let mut grow = |buf: &mut Option<wgpu::Buffer>, used: u64, need: u64, unit: u64, usage, label| {
            if buf.as_ref().is_some_and(|b| b.size() >= need * unit) {
                return;
            }
            let size = (need * unit * 3 / 2).min(max / unit * unit).max(need * unit).max(unit);
            let new = d.create_buffer(&wgpu::BufferDescriptor {
                label: Some(label),
                size: size.next_multiple_of(wgpu::COPY_BUFFER_ALIGNMENT),
                usage: usage | wgpu::BufferUsages::COPY_DST | wgpu::BufferUsages::COPY_SRC,
                mapped_at_creation: false,
            });
            if let Some(old) = buf.as_ref().filter(|_| used > 0) {
                enc.copy_buffer_to_buffer(old, 0, &new, 0, used * unit);
            }
            *buf = Some(new);
        };
        grow(&mut self.vertices, self.nv, nv, VERTEX_BYTES, wgpu::BufferUsages::VERTEX, "iso_pool_vertices");
        grow(&mut self.indices, self.nt, nt, TRIANGLE_BYTES, wgpu::BufferUsages::INDEX, "iso_pool_indices");
        // Each fresh patch's place, then its data, filled in parallel.
        let mut bases = Vec::with_capacity(fresh.len());
        let (mut v, mut t) = (self.nv as u32, self.nt as u32);
        for (&nv, &nt) in vlens.iter().zip(&tlens) {
            bases.push((v, t));
            (v, t) = (v + nv as u32, t + nt as u32);
        }
        let verts = fill_parts(&vlens, |i, out| pack_vertices(fresh[i], space, out));
        let tris = fill_parts(&tlens, |i, out| offset_triangles(fresh[i], None, bases[i].0, out));
        let (vbuf, ibuf) = self.buffers().expect("grown above");
        ctx.queue.write_buffer(vbuf, self.nv * VERTEX_BYTES, bytemuck::cast_slice(&verts));
        ctx.queue.write_buffer(ibuf, self.nt * TRIANGLE_BYTES, bytemuck::cast_slice(&tris));
        for (p, &(vbase, tbase)) in fresh.iter().zip(&bases) {
            self.slots.insert(address(p), Slot { patch: Arc::downgrade(p), vbase, tbase });
        }
        (self.nv, self.nt) = (nv, nt);
        Ok(())
    }
}

/// [`super::passes::draw_surface`] from the renderer's pool ([`SurfacePool`]): `patches` are put
/// in the pool (only those not there yet are uploaded), then drawn whole (`ranges` None: runs of
/// patches consecutive in the pool, one draw each) or, with `ranges`, only those triangle ranges
/// of each patch (their indices uploaded). Returns (triangles drawn, vertices of the patches).
#[allow(clippy::too_many_arguments)]
pub(super) fn draw_pooled(
    ctx: &GpuContext,
    iso: &IsoPasses,
    pool: &mut SurfacePool,
    globals_bg: &wgpu::BindGroup,
    tg: &Targets,
    patches: &[Arc<SurfacePatch>],
    ranges: Option<&[Vec<[u32; 2]>]>,
    space: &Space,
) -> Result<(u64, u64)> {
    let d = &ctx.device;
    let mut enc = d.create_command_encoder(&wgpu::CommandEncoderDescriptor { label: Some("iso_surface") });
    let bases = pool.ensure(ctx, &mut enc, patches, space)?;
    let nv: u64 = patches.iter().map(|p| p.positions.len() as u64).sum();
    let counts = triangle_counts(patches, ranges);
    let nt = counts.iter().sum::<usize>() as u64;
    // Triangle runs of the pool's index buffer, or this frame's own indices.
    let mut runs: Vec<std::ops::Range<u32>> = Vec::new();
    let own = match ranges {
        None => {
            let mut order: Vec<(u32, u32)> =
                patches.iter().zip(&bases).map(|(p, &(_, t))| (t, t + p.triangles.len() as u32)).collect();
            order.sort_unstable();
            for (a, b) in order {
                match runs.last_mut() {
                    Some(r) if r.end == 3 * a => r.end = 3 * b,
                    _ if a < b => runs.push(3 * a..3 * b),
                    _ => {}
                }
            }
            None
        }
        Some(ranges) => {
            let idx = fill_parts(&counts, |i, out| offset_triangles(&patches[i], Some(&ranges[i]), bases[i].0, out));
            runs.push(0..3 * nt as u32);
            (nt > 0).then(|| index_buffer(d, &idx))
        }
    };
    let buffers = pool.buffers().map(|(vb, pool_ib)| (vb, own.as_ref().unwrap_or(pool_ib)));
    submit_surface(ctx, iso, globals_bg, tg, enc, buffers, &runs)?;
    Ok((nt, nv))
}
