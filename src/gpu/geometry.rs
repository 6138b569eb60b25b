//! The scene's geometry on the GPU: one vertex buffer and one index buffer for every tile of
//! every object, the tile → object table, and each tile's fine and coarse draw.

use super::layout::DrawArgs;
use super::readback::map_err;
use super::GpuContext;
use crate::error::{Error, Result};
use crate::scene::Scene;
use glam::DVec3;
use wgpu::util::DeviceExt;

/// GPU copy of a scene's geometry, keyed by [`Scene::geometry_key`].
pub struct SceneGeometry {
    pub key: (u64, u64),
    pub vertices: Option<wgpu::Buffer>,
    /// Per vertex, in `vertices`' order, the lit pass's second vertex stream: an f32 scalar (the
    /// tiles' `values` for colour by data; 0 for tiles without; no data as [`NO_DATA`]) and the
    /// packed smooth normal (`TileMesh::normals`; `lod::normals::NONE` for tiles without), or for
    /// a grid-shaded mesh (`grid_dims`) the packed grid coordinates (`TileMesh::grid_uv`).
    pub values: Option<wgpu::Buffer>,
    pub indices: Option<wgpu::Buffer>,
    /// Object index (position in `scene.objects()`) of every tile.
    pub tile_object: wgpu::Buffer,
    pub tile_object_cpu: Vec<u32>,
    /// The fine (level 0) draw of every tile, in tile order.
    pub fine: Vec<DrawArgs>,
    /// The coarse proxy's draw of every tile (its own compact vertex copy).
    pub coarse: Vec<DrawArgs>,
    /// Per tile, the draws of its LOD levels 1.. (`TileMesh::levels`, each with its own compact
    /// vertex copy) and their errors.
    pub levels: Vec<Vec<LevelDraw>>,
    /// Origin-relative tile bounds (no offset, no exaggeration), for front-to-back ordering.
    pub bbox: Vec<(DVec3, DVec3)>,
    /// The fine surfaces of the height fields as the lit pass samples them
    /// (`Object::shading_samples`), object after object, two words per sample: the gradient as
    /// two f16 (x in the low half) and the object-relative height's f32 bits.
    pub shading: wgpu::Buffer,
    /// Per object (scene order), the first sample of its gradients in `shading`; None for objects
    /// without (meshes, grids; height fields past the device's storage-binding limit), which the
    /// lit pass shades with their facets' normals.
    pub shading_base: Vec<Option<u32>>,
    /// Per object, (columns, rows) of a structured grid mesh whose fine normals are in `shading`
    /// (`Object::grid_normals`: one sample per grid vertex, the packed normal then 0), whose
    /// vertices carry their grid coordinates in place of their normals; None for other objects.
    pub grid_dims: Vec<Option<(u32, u32)>>,
    pub bytes: u64,
}

/// The draw of one LOD level of a tile and its errors (`lod::levels::Level`).
#[derive(Clone, Copy, Debug)]
pub struct LevelDraw {
    pub args: DrawArgs,
    /// Geometric error, world units (not exaggerated).
    pub error: f32,
    /// Shading error, a normal chord (unitless; `lod::shading`).
    pub shading_error: f32,
}

/// The scalar uploaded for a NaN value (no data): WGSL may assume no NaN at run time, so no data
/// travels as the most negative f32, which the lit pass tests for (`s < -1e37`) and which any
/// interpolation with it keeps below that (a triangle touching no data is no data).
pub const NO_DATA: f32 = -f32::MAX;

/// The normal map of the lit pass: every height field's shading samples and every structured
/// grid mesh's fine normals, as long as they fit one storage binding (later height fields fall
/// back to facet normals and vertex heights, later grid meshes to their vertex normals).
#[allow(clippy::type_complexity)]
fn upload_shading(ctx: &GpuContext, scene: &Scene) -> (wgpu::Buffer, Vec<Option<u32>>, Vec<Option<(u32, u32)>>) {
    let max_words = ctx.limits.max_storage_buffer_binding_size / 4;
    let pack = |[gx, gy, z]: [f32; 3]| {
        let h = |v: f32| u32::from(half::f16::from_f32(v).to_bits());
        [h(gx) | (h(gy) << 16), z.to_bits()]
    };
    let mut words: Vec<u32> = Vec::new();
    let mut dims = vec![None; scene.objects().len()];
    let base = scene
        .objects()
        .iter()
        .enumerate()
        .map(|(oi, o)| {
            if let Some((nu, nv, normals)) = o.grid_normals() {
                if (words.len() + 2 * normals.len()) as u64 > max_words {
                    return None;
                }
                let first = (words.len() / 2) as u32;
                words.extend(normals.into_iter().flat_map(|n| [n, 0]));
                dims[oi] = Some((nu as u32, nv as u32));
                return Some(first);
            }
            let g = o.shading_samples()?;
            if (words.len() + 2 * g.len()) as u64 > max_words {
                return None;
            }
            let first = (words.len() / 2) as u32;
            words.extend(g.into_iter().flat_map(pack));
            Some(first)
        })
        .collect();
    if words.is_empty() {
        words.extend([0, 0]);
    }
    let buf = ctx.device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
        label: Some("shading"),
        contents: bytemuck::cast_slice(&words),
        usage: wgpu::BufferUsages::STORAGE,
    });
    (buf, base, dims)
}

/// Checks that a scene of `nv` vertices and `ni` indices fits one vertex and one index buffer of
/// at most `max` bytes, with u32 indices and offsets: a clear error rather than a wrong image.
pub fn check_buffer_sizes(nv: u64, ni: u64, max: u64) -> Result<()> {
    if nv * 12 > max || ni * 4 > max || nv > u32::MAX as u64 || ni > u32::MAX as u64 {
        return Err(Error::Device(format!(
            "scene too large for one GPU buffer on this device: {} MiB of vertices ({nv}), {} MiB of indices ({ni}), \
             limit {} MiB per buffer and 2^32 elements; split it into several scenes or reduce its resolution",
            (nv * 12) >> 20,
            (ni * 4) >> 20,
            max >> 20
        )));
    }
    Ok(())
}

impl SceneGeometry {
    pub fn n_tiles(&self) -> usize {
        self.fine.len()
    }

    /// Fine (level 0) triangles over every tile.
    pub fn fine_triangles(&self) -> u64 {
        self.fine.iter().map(|a| a.index_count as u64 / 3).sum()
    }

    /// Uploads `scene`'s geometry. Sizes are computed first (the coarse proxies get compact
    /// copies of the vertices they use), so that the geometry is written straight into mapped
    /// GPU buffers without host temporaries.
    pub fn upload(ctx: &GpuContext, scene: &Scene) -> Result<Self> {
        let d = &ctx.device;
        let (mut nv, mut ni) = (0u64, 0u64);
        let mut seen: Vec<bool> = Vec::new();
        for t in scene.objects().iter().flat_map(|o| &o.tiles) {
            nv += t.positions.len() as u64;
            ni += t.fine.len() as u64;
            for idx in std::iter::once(&t.coarse).chain(t.levels.iter().map(|l| &l.indices)) {
                seen.clear();
                seen.resize(t.positions.len(), false);
                nv += idx.iter().filter(|&&k| !std::mem::replace(&mut seen[k as usize], true)).count() as u64;
                ni += idx.len() as u64;
            }
        }
        check_buffer_sizes(nv, ni, ctx.limits.max_buffer_size)?;
        let mapped = |label: &str, size: u64, usage: wgpu::BufferUsages| {
            (size > 0).then(|| {
                d.create_buffer(&wgpu::BufferDescriptor { label: Some(label), size, usage, mapped_at_creation: true })
            })
        };
        let direct = if ctx.features.contains(wgpu::Features::MAPPABLE_PRIMARY_BUFFERS) {
            wgpu::BufferUsages::MAP_WRITE
        } else {
            wgpu::BufferUsages::empty()
        };
        let vb = mapped("vertices", nv * 12, wgpu::BufferUsages::VERTEX | direct);
        let sb = mapped("values", nv * 8, wgpu::BufferUsages::VERTEX | direct);
        let ib = mapped("indices", ni * 4, wgpu::BufferUsages::INDEX | direct);
        let (mut fine, mut coarse, mut tile_object, mut bbox) = (Vec::new(), Vec::new(), Vec::new(), Vec::new());
        let mut levels = Vec::new();
        let (shading, shading_base, grid_dims) = upload_shading(ctx, scene);
        let tile_bbox = |t: &crate::lod::TileMesh| {
            (DVec3::from_array(t.bbox_min.map(f64::from)), DVec3::from_array(t.bbox_max.map(f64::from)))
        };
        if let (Some(vb), Some(sb), Some(ib)) = (&vb, &sb, &ib) {
            let mut vmap = vb.slice(..).get_mapped_range_mut().map_err(map_err)?;
            let mut smap = sb.slice(..).get_mapped_range_mut().map_err(map_err)?;
            let mut imap = ib.slice(..).get_mapped_range_mut().map_err(map_err)?;
            // Mapped memory is write-only: append whole runs, counting in vertices and indices.
            let (mut v, mut i) = (0usize, 0usize);
            // Positions and their (scalar, normal) pairs (zeros when the tile has none), run for run.
            let mut scratch: Vec<[u32; 2]> = Vec::new();
            let mut put_v = |v: &mut usize, data: &[[f32; 3]], vals: &[f32], normals: &[u32]| {
                vmap.slice(*v * 12..(*v + data.len()) * 12).copy_from_slice(bytemuck::cast_slice(data));
                scratch.clear();
                scratch.extend((0..data.len()).map(|k| {
                    let x = vals.get(k).map_or(0.0, |&x| if x.is_nan() { NO_DATA } else { x });
                    [x.to_bits(), normals.get(k).copied().unwrap_or(crate::lod::normals::NONE)]
                }));
                smap.slice(*v * 8..(*v + data.len()) * 8).copy_from_slice(bytemuck::cast_slice(&scratch));
                *v += data.len();
            };
            let mut put_i = |i: &mut usize, data: &[u32]| {
                imap.slice(*i * 4..(*i + data.len()) * 4).copy_from_slice(bytemuck::cast_slice(data));
                *i += data.len();
            };
            let (mut remap, mut cverts, mut cidx): (Vec<u32>, Vec<[f32; 3]>, Vec<u32>) =
                (Vec::new(), Vec::new(), Vec::new());
            let mut cvals: Vec<f32> = Vec::new();
            let mut cnormals: Vec<u32> = Vec::new();
            for (oi, o) in scene.objects().iter().enumerate() {
                for t in &o.tiles {
                    // A grid-shaded mesh's vertices carry their grid coordinates for its normals.
                    let nrm: &[u32] = if grid_dims[oi].is_some() { &t.grid_uv } else { &t.normals };
                    let tile = fine.len() as u32;
                    fine.push(DrawArgs {
                        index_count: t.fine.len() as u32,
                        instance_count: 1,
                        first_index: i as u32,
                        base_vertex: v as i32,
                        first_instance: tile,
                    });
                    put_v(&mut v, &t.positions, &t.values, nrm);
                    put_i(&mut i, &t.fine);
                    // The coarse proxy and each LOD level get their own compact copy of the
                    // vertices they use: software rasterisers (llvmpipe) shade every vertex in an
                    // indexed draw's index range, so indexing into the fine vertices would make
                    // them cost as much as a fine draw.
                    let mut compact = |indices: &[u32], v: &mut usize, i: &mut usize| {
                        remap.clear();
                        remap.resize(t.positions.len(), u32::MAX);
                        cverts.clear();
                        cvals.clear();
                        cnormals.clear();
                        cidx.clear();
                        for &k in indices {
                            let slot = &mut remap[k as usize];
                            if *slot == u32::MAX {
                                *slot = cverts.len() as u32;
                                cverts.push(t.positions[k as usize]);
                                if !t.values.is_empty() {
                                    cvals.push(t.values[k as usize]);
                                }
                                if !nrm.is_empty() {
                                    cnormals.push(nrm[k as usize]);
                                }
                            }
                            cidx.push(*slot);
                        }
                        let args = DrawArgs {
                            index_count: cidx.len() as u32,
                            instance_count: 1,
                            first_index: *i as u32,
                            base_vertex: *v as i32,
                            first_instance: tile,
                        };
                        put_v(v, &cverts, &cvals, &cnormals);
                        put_i(i, &cidx);
                        args
                    };
                    coarse.push(compact(&t.coarse, &mut v, &mut i));
                    levels.push(
                        t.levels
                            .iter()
                            .map(|l| LevelDraw {
                                args: compact(&l.indices, &mut v, &mut i),
                                error: l.error,
                                shading_error: l.shading_error,
                            })
                            .collect(),
                    );
                    tile_object.push(oi as u32);
                    bbox.push(tile_bbox(t));
                }
            }
            debug_assert_eq!((v as u64, i as u64), (nv, ni));
        } else {
            // No triangles anywhere: keep the tile table (all tiles empty).
            for (oi, o) in scene.objects().iter().enumerate() {
                for t in &o.tiles {
                    let tile = fine.len() as u32;
                    fine.push(DrawArgs { first_instance: tile, ..Default::default() });
                    coarse.push(DrawArgs { first_instance: tile, ..Default::default() });
                    levels.push(Vec::new());
                    tile_object.push(oi as u32);
                    bbox.push(tile_bbox(t));
                }
            }
        }
        for b in vb.iter().chain(sb.iter()).chain(ib.iter()) {
            b.unmap();
        }
        // Storage buffers may not be empty: pad with one element.
        let to = if tile_object.is_empty() { vec![0u32] } else { tile_object.clone() };
        let tob = d.create_buffer_init(&wgpu::util::BufferInitDescriptor {
            label: Some("tile_object"),
            contents: bytemuck::cast_slice(&to),
            usage: wgpu::BufferUsages::STORAGE,
        });
        let bytes = nv * 20 + ni * 4 + to.len() as u64 * 4 + shading.size();
        ctx.take_error()?;
        Ok(Self {
            key: scene.geometry_key(),
            vertices: vb,
            values: sb,
            indices: ib,
            tile_object: tob,
            tile_object_cpu: tile_object,
            fine,
            coarse,
            levels,
            bbox,
            shading,
            shading_base,
            grid_dims,
            bytes,
        })
    }

    /// Squared distance from `eye` (render space) to each tile's box, with the objects' offsets
    /// and the exaggeration `z_scale` applied: the key of front-to-back orders.
    pub fn eye_distances(&self, scene: &Scene, origin: DVec3, eye: DVec3, z_scale: f64) -> Vec<f64> {
        let zs = DVec3::new(1.0, 1.0, z_scale);
        let objects = scene.objects();
        self.bbox
            .iter()
            .zip(&self.tile_object_cpu)
            .map(|((lo, hi), &oi)| {
                let off = objects[oi as usize].placement(origin);
                let (lo, hi) = ((*lo + off) * zs, (*hi + off) * zs);
                (eye.clamp(lo, hi) - eye).length_squared()
            })
            .collect()
    }
}
