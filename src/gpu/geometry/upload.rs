//! [`SceneGeometry::upload`] in stages: the normal map and per-sample values, the plan of what
//! is written, the mapped vertex and index buffers filled tile by tile, the slabs, the tables.

use super::plan::Plan;
use super::{
    check_buffer_sizes, draw_runs, normal_slot, scalar_slot, scalar_word, tile_bbox, tile_sub_boxes, vertex_words,
    write_shading, CompactDraw, LevelDraw, SceneGeometry, SlabDraw, VariantSet, NO_VARIANTS, SHADING_ROW,
};
use crate::error::Result;
use crate::gpu::layout::DrawArgs;
use crate::gpu::readback::map_err;
use crate::gpu::GpuContext;
use crate::lod::slab::ShellVertex;
use crate::scene::Scene;
use rayon::prelude::*;
use wgpu::util::DeviceExt;

/// The normal map of the lit pass: every height field's shading samples and every structured
/// grid mesh's fine normals, as long as they fit the texture ([`SHADING_ROW`] samples a row, as
/// many rows as the device's 2D textures take; later height fields fall back to facet normals and
/// vertex heights, later grid meshes to their vertex normals). Returns the texture (per sample
/// the gradients or the normal, then the height or 0), each object's first sample, and each grid
/// mesh's grid size.
#[allow(clippy::type_complexity)]
fn upload_shading(
    ctx: &GpuContext,
    scene: &Scene,
) -> Result<(wgpu::Texture, Vec<Option<u32>>, Vec<Option<(u32, u32)>>)> {
    let max_rows = ctx.limits.max_texture_dimension_2d.max(1) as u64;
    let max_samples = (SHADING_ROW as u64 * max_rows).min(u32::MAX as u64);
    let mut total = 0u64;
    let mut dims = vec![None; scene.objects().len()];
    // Per object in the map: its sample count and, for a grid mesh, its fine normals (small:
    // faults), until they are written.
    let mut parts: Vec<(usize, u64, Option<Vec<u32>>)> = Vec::new();
    let base: Vec<Option<u32>> = scene
        .objects()
        .iter()
        .enumerate()
        .map(|(oi, o)| {
            let (n, normals) = match o.heightfield() {
                Some(hf) => ((hf.nx * hf.ny) as u64, None),
                None => {
                    let (nu, nv, normals) = o.grid_normals()?;
                    dims[oi] = Some((nu as u32, nv as u32));
                    ((nu * nv) as u64, Some(normals))
                }
            };
            if total + n > max_samples {
                dims[oi] = None;
                return None;
            }
            total += n;
            parts.push((oi, n, normals));
            Some((total - n) as u32)
        })
        .collect();
    let (width, height) = (total.clamp(1, SHADING_ROW as u64) as u32, total.div_ceil(SHADING_ROW as u64).max(1) as u32);
    let usage = wgpu::TextureUsages::TEXTURE_BINDING | wgpu::TextureUsages::COPY_DST;
    let texture =
        crate::gpu::targets::texture(&ctx.device, "shading", width, height, wgpu::TextureFormat::Rg32Uint, usage);
    let h = |v: f32| u32::from(half::f16::from_f32(v).to_bits());
    let samples = |(oi, _, normals): &(usize, u64, Option<Vec<u32>>)| -> Vec<[u32; 2]> {
        match normals {
            // A grid mesh: its packed fine normal, then 0.
            Some(normals) => normals.iter().map(|&n| [n, 0]).collect(),
            None => {
                let mut out = Vec::new();
                scene.objects()[*oi]
                    .for_each_shading_sample(|[gx, gy, z]| out.push([h(gx) | (h(gy) << 16), z.to_bits()]));
                out
            }
        }
    };
    // As many objects at a time as there are threads, each into a vector of its own, then
    // written and submitted (the driver's staging copies are freed batch by batch).
    let mut at = 0u64;
    for batch in parts.chunks(rayon::current_num_threads().max(1)) {
        for words in batch.par_iter().map(samples).collect::<Vec<_>>() {
            write_shading(&ctx.queue, &texture, at, &words);
            at += words.len() as u64;
        }
        ctx.queue.submit(std::iter::empty());
    }
    Ok((texture, base, dims))
}

/// The per-sample values of the height fields coloured by data (`SceneGeometry::sample_values`)
/// and each object's first sample in them, for those whose heights are in the normal map
/// (`shading_base`), as long as they fit the texture ([`SHADING_ROW`] words a row, as many rows
/// as the device's 2D textures take; later ones keep vertices of their own).
/// Then the cell values of grids coloured per fragment ([`crate::gpu::cell_values`]).
fn upload_values(
    ctx: &GpuContext,
    scene: &Scene,
    shading_base: &[Option<u32>],
) -> (wgpu::Texture, Vec<Option<u32>>, crate::gpu::cell_values::CellTables) {
    let max_words = (SHADING_ROW as u64 * ctx.limits.max_texture_dimension_2d.max(1) as u64).min(u32::MAX as u64);
    let mut words: Vec<f32> = Vec::new();
    let base = scene
        .objects()
        .iter()
        .zip(shading_base)
        .map(|(o, b)| {
            b.as_ref()?;
            let v = o.value_grid()?;
            if (words.len() + v.len()) as u64 > max_words {
                return None;
            }
            let first = words.len() as u32;
            words.extend(v.into_iter().map(scalar_word));
            Some(first)
        })
        .collect();
    let cells = crate::gpu::cell_values::append(scene, &mut words, max_words, scalar_word);
    let (extent, words) = crate::gpu::layout::rows(&words, SHADING_ROW as usize);
    let texture = crate::gpu::layout::table_texture(ctx, "sample_values", wgpu::TextureFormat::R32Uint, extent, &words);
    (texture, base, cells)
}

/// The slabs of `scene`'s tiles and their gates (`Object::slabs`: built here for a scene read from
/// bytes) in one vertex and one index buffer, and per tile its slab's draws
/// (`SceneGeometry::slab_draws`).
fn upload_slabs(d: &wgpu::Device, scene: &Scene) -> (Option<(wgpu::Buffer, wgpu::Buffer)>, Vec<Option<SlabDraw>>) {
    let (mut verts, mut idx): (Vec<ShellVertex>, Vec<u32>) = (Vec::new(), Vec::new());
    let mut push = |tile: usize, v: &[ShellVertex], ix: &[u32]| {
        let args = DrawArgs {
            index_count: ix.len() as u32,
            instance_count: 1,
            first_index: idx.len() as u32,
            base_vertex: verts.len() as i32,
            first_instance: tile as u32,
        };
        verts.extend_from_slice(v);
        idx.extend_from_slice(ix);
        args
    };
    let slabs = scene.objects().iter().flat_map(|o| (0..o.tiles.len()).map(|t| o.slab(t)));
    let draws: Vec<Option<SlabDraw>> = slabs
        .enumerate()
        .map(|(i, s)| {
            let s = s?;
            let args = push(i, &s.vertices, &s.indices);
            let gate = (!s.gate.indices.is_empty()).then(|| push(i, &s.gate.vertices, &s.gate.indices));
            let corners = s.vertices.iter().chain(&s.gate.vertices).map(|v| glam::DVec3::from(v.pos.map(f64::from)));
            let bounds =
                corners.fold((glam::DVec3::INFINITY, glam::DVec3::NEG_INFINITY), |(lo, hi), p| (lo.min(p), hi.max(p)));
            Some(SlabDraw { args, gate, exact: s.levels_exact, bounds })
        })
        .collect();
    if idx.is_empty() {
        return (None, draws);
    }
    let buf = |label, contents: &[u8], usage| {
        d.create_buffer_init(&wgpu::util::BufferInitDescriptor { label: Some(label), contents, usage })
    };
    let vb = buf("slab_vertices", bytemuck::cast_slice(&verts), wgpu::BufferUsages::VERTEX);
    let ib = buf("slab_indices", bytemuck::cast_slice(&idx), wgpu::BufferUsages::INDEX);
    (Some((vb, ib)), draws)
}

/// The per-tile tables the upload builds, one entry per tile in draw order.
#[derive(Default)]
struct TileDraws {
    fine: Vec<DrawArgs>,
    coarse: Vec<DrawArgs>,
    occluder: Vec<DrawArgs>,
    levels: Vec<Vec<LevelDraw>>,
    variant_sets: Vec<VariantSet>,
    tile_object: Vec<u32>,
    bbox: Vec<(glam::DVec3, glam::DVec3)>,
    own_vertices: Vec<Vec<u32>>,
}

impl SceneGeometry {
    /// Uploads `scene`'s geometry. Sizes are computed first (the coarse proxies and LOD levels get
    /// compact copies of the vertices they use; the draws of lattice tiles become shared
    /// patterns), so that the geometry is written straight into mapped GPU buffers without host
    /// temporaries beyond the patterns.
    pub fn upload(ctx: &GpuContext, scene: &Scene) -> Result<Self> {
        let d = &ctx.device;
        let (shading, shading_base, grid_dims) = upload_shading(ctx, scene)?;
        let (sample_values, values_base, cells) = upload_values(ctx, scene, &shading_base);
        let mut plan = Plan::new(scene, &shading_base, &values_base);
        cell_table_grid(&mut plan, &cells);
        let (nv, ni) = (plan.nv, plan.ni);
        check_buffer_sizes(nv, ni, ctx.limits.max_buffer_size)?;
        let (vb, sb, ib) = mapped_buffers(ctx, nv, ni);
        let mut draws = TileDraws::default();
        if let (Some(vb), Some(sb), Some(ib)) = (&vb, &sb, &ib) {
            write_tiles(scene, &plan, &grid_dims, &cells.logs, [vb, sb, ib], &mut draws)?;
        } else {
            empty_tiles(scene, &mut draws);
        }
        for b in vb.iter().chain(sb.iter()).chain(ib.iter()) {
            b.unmap();
        }
        let TileDraws { fine, coarse, occluder, levels, variant_sets, tile_object, bbox, own_vertices } = draws;
        let max_tiles = crate::gpu::layout::TILES_PER_ROW as u64 * ctx.limits.max_texture_dimension_2d as u64;
        if tile_object.len() as u64 > max_tiles {
            return Err(crate::error::Error::Device(format!(
                "scene has {} tiles, more than this device's tile table holds ({max_tiles}); split it into several scenes \
                 or reduce its resolution",
                tile_object.len()
            )));
        }
        let (extent, texels) = crate::gpu::layout::tile_texels(&plan.tile_grid, &tile_object);
        let tile_texture =
            crate::gpu::layout::table_texture(ctx, "tiles", wgpu::TextureFormat::Rgba32Uint, extent, &texels);
        let tiles: Vec<&crate::lod::TileMesh> = scene.objects().iter().flat_map(|o| &o.tiles).collect();
        let height_blocks: Vec<_> = scene.objects().iter().flat_map(|o| o.height_blocks()).collect();
        let sub_boxes = tiles.par_iter().zip(&height_blocks).map(|(t, b)| tile_sub_boxes(t, b.as_deref())).collect();
        let (slabs, slab_draws) = upload_slabs(d, scene);
        let slab_bytes = slabs.as_ref().map_or(0, |(v, i)| v.size() + i.size());
        let bytes = nv * 24 + ni * 4 + texels.len() as u64 * 16;
        let texel_count = |t: &wgpu::Texture| t.width() as u64 * t.height() as u64;
        let bytes = bytes + 8 * texel_count(&shading) + 4 * texel_count(&sample_values) + slab_bytes;
        let draw_runs = draw_runs(scene, &tile_object, &shading_base, &grid_dims, &cells.objects);
        ctx.take_error()?;
        Ok(Self {
            key: scene.geometry_key(),
            vertices: vb,
            values: sb,
            indices: ib,
            tiles: tile_texture,
            tile_object_cpu: tile_object,
            sample_values,
            fine,
            coarse,
            occluder,
            levels,
            variant_sets,
            bbox,
            sub_boxes,
            height_blocks,
            slab_draws,
            slabs,
            shading,
            shading_base,
            grid_dims,
            table_colors: cells.objects,
            log_colors: cells.logs,
            draw_runs,
            bytes,
            clearance: Default::default(),
            own_vertices,
        })
    }
}

/// Grid tiles with cell tables (drawn from vertices of their own): the table's columns and
/// first word where the vertex stage would look for a lattice (common.wgsl `tile_grid_at`).
fn cell_table_grid(plan: &mut Plan, cells: &crate::gpu::cell_values::CellTables) {
    let none = f32::from_bits(u32::MAX);
    for (t, c) in cells.tiles.iter().enumerate() {
        if let Some([first, bw, bh]) = *c {
            plan.tile_grid[3 * t + 1] = [f32::from_bits(bw), f32::from_bits(bh), none, 0.0];
            plan.tile_grid[3 * t + 2] = [none, f32::from_bits(first), 0.0, 0.0];
        }
    }
}

/// The vertex, value and index buffers of `nv` vertices and `ni` indices, mapped for writing
/// (None where empty).
fn mapped_buffers(
    ctx: &GpuContext,
    nv: u64,
    ni: u64,
) -> (Option<wgpu::Buffer>, Option<wgpu::Buffer>, Option<wgpu::Buffer>) {
    let d = &ctx.device;
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
    // COPY_DST: an object whose geometry is replaced in place is written by `patch`.
    let dst = wgpu::BufferUsages::COPY_DST;
    let vb = mapped("vertices", nv * 12, wgpu::BufferUsages::VERTEX | dst | direct);
    let sb = mapped("values", nv * 12, wgpu::BufferUsages::VERTEX | dst | direct);
    let ib = mapped("indices", ni * 4, wgpu::BufferUsages::INDEX | dst | direct);
    (vb, sb, ib)
}

/// Writes the plan's patterns, then every tile's draws, into the mapped vertex, value and index
/// buffers (`[vb, sb, ib]`), and fills `draws`. A well coloured by a log (`TileMesh::stations`)
/// whose tables did not fit (`logs` false) is drawn at level 0 alone: its levels keep level 0's
/// colours only through the tables.
fn write_tiles(
    scene: &Scene,
    plan: &Plan,
    grid_dims: &[Option<(u32, u32)>],
    logs: &[bool],
    [vb, sb, ib]: [&wgpu::Buffer; 3],
    draws: &mut TileDraws,
) -> Result<()> {
    let TileDraws { fine, coarse, occluder, levels, variant_sets, tile_object, bbox, own_vertices } = draws;
    let mut sets: std::collections::HashMap<Vec<usize>, u32> = std::collections::HashMap::new();
    let mut vmap = vb.slice(..).get_mapped_range_mut().map_err(map_err)?;
    let mut smap = sb.slice(..).get_mapped_range_mut().map_err(map_err)?;
    let mut imap = ib.slice(..).get_mapped_range_mut().map_err(map_err)?;
    // Mapped memory is write-only: append whole runs, counting in vertices and indices.
    let (mut v, mut i) = (0usize, 0usize);
    // Positions and their (scalar, normal) pairs (zeros when the tile has none), run for run.
    let mut scratch: Vec<[u32; 3]> = Vec::new();
    let mut put_v = |v: &mut usize, data: &[[f32; 3]], vals: &[f32], normals: &[u32], ring_z: &[f32]| {
        vmap.slice(*v * 12..(*v + data.len()) * 12).copy_from_slice(bytemuck::cast_slice(data));
        vertex_words(data.len(), vals, normals, ring_z, &mut scratch);
        smap.slice(*v * 12..(*v + data.len()) * 12).copy_from_slice(bytemuck::cast_slice(&scratch));
        *v += data.len();
    };
    let mut put_i = |i: &mut usize, data: &[u32]| {
        imap.slice(*i * 4..(*i + data.len()) * 4).copy_from_slice(bytemuck::cast_slice(data));
        *i += data.len();
    };
    // The patterns first: vertices (column, row, 0) as exact floats (common.wgsl).
    let mut pattern_args = Vec::with_capacity(plan.patterns.len());
    let mut cverts: Vec<[f32; 3]> = Vec::new();
    for (verts, idx) in &plan.patterns {
        pattern_args.push(DrawArgs {
            index_count: idx.len() as u32,
            instance_count: 1,
            first_index: i as u32,
            base_vertex: v as i32,
            first_instance: 0,
        });
        cverts.clear();
        cverts.extend(verts.iter().map(|&[a, b]| [a as f32, b as f32, 0.0]));
        put_v(&mut v, &cverts, &[], &[], &[]);
        put_i(&mut i, idx);
    }
    let mut cd = CompactDraw::default();
    let mut runs = plan.runs.iter();
    for (oi, o) in scene.objects().iter().enumerate() {
        for t in &o.tiles {
            let nrm = normal_slot(grid_dims[oi].is_some(), t);
            let vals = scalar_slot(logs[oi], t);
            let tile = fine.len() as u32;
            tile_object.push(oi as u32);
            bbox.push(tile_bbox(t));
            if let Some(ids) = runs.next().expect("one plan per tile") {
                let args = |p: usize| DrawArgs { first_instance: tile, ..pattern_args[p] };
                fine.push(args(ids[0]));
                coarse.push(args(ids[1]));
                occluder.push(args(*ids.last().expect("fine, coarse, levels, occluder")));
                let mut next = ids[2..].iter();
                levels.push(
                    t.levels
                        .iter()
                        .map(|l| {
                            let level = args(*next.next().expect("a pattern per level list"));
                            let ids: Vec<usize> =
                                (0..l.grouped.len()).map(|_| *next.next().expect("a pattern per variant")).collect();
                            let grouped = match ids.len() {
                                0 => NO_VARIANTS,
                                _ => *sets.entry(ids).or_insert_with_key(|ids| {
                                    let mut set = VariantSet::default();
                                    for (a, &p) in set.iter_mut().zip(ids) {
                                        *a = DrawArgs { first_instance: 0, ..pattern_args[p] };
                                    }
                                    variant_sets.push(set);
                                    variant_sets.len() as u32 - 1
                                }),
                            };
                            LevelDraw {
                                args: level,
                                error: l.error,
                                error_z: l.error_z,
                                shading_error: l.shading_error,
                                grouped,
                                grouped_error: l.grouped_error,
                            }
                        })
                        .collect(),
                );
                own_vertices.push(Vec::new());
                continue;
            }
            occluder.push(DrawArgs { first_instance: tile, ..Default::default() });
            fine.push(DrawArgs {
                index_count: t.fine.len() as u32,
                instance_count: 1,
                first_index: i as u32,
                base_vertex: v as i32,
                first_instance: tile,
            });
            put_v(&mut v, &t.positions, vals, nrm, &t.ring_z);
            put_i(&mut i, &t.fine);
            // The coarse proxy and each LOD level get their own compact copy of the
            // vertices they use: software rasterisers (llvmpipe) shade every vertex in an
            // indexed draw's index range, so indexing into the fine vertices would make
            // them cost as much as a fine draw.
            let mut counts = vec![t.positions.len() as u32];
            let mut compact = |indices: &[u32], v: &mut usize, i: &mut usize| {
                cd.build(t, (vals, nrm), indices);
                counts.push(cd.verts.len() as u32);
                let args = DrawArgs {
                    index_count: cd.idx.len() as u32,
                    instance_count: 1,
                    first_index: *i as u32,
                    base_vertex: *v as i32,
                    first_instance: tile,
                };
                put_v(v, &cd.verts, &cd.vals, &cd.normals, &cd.ring_z);
                put_i(i, &cd.idx);
                args
            };
            coarse.push(compact(&t.coarse, &mut v, &mut i));
            levels.push(
                t.levels
                    .iter()
                    .map(|l| LevelDraw {
                        args: compact(&l.indices, &mut v, &mut i),
                        error: l.error,
                        error_z: l.error_z,
                        shading_error: l.shading_error,
                        grouped: NO_VARIANTS,
                        grouped_error: l.error,
                    })
                    .collect(),
            );
            if !logs[oi] && !t.stations.is_empty() {
                levels.last_mut().expect("this tile's levels").clear();
            }
            own_vertices.push(counts);
        }
    }
    debug_assert_eq!((v as u64, i as u64), (plan.nv, plan.ni));
    Ok(())
}

/// No triangles anywhere: keep the tile table (all tiles empty).
fn empty_tiles(scene: &Scene, draws: &mut TileDraws) {
    for (oi, o) in scene.objects().iter().enumerate() {
        for t in &o.tiles {
            let tile = draws.fine.len() as u32;
            draws.fine.push(DrawArgs { first_instance: tile, ..Default::default() });
            draws.coarse.push(DrawArgs { first_instance: tile, ..Default::default() });
            draws.occluder.push(DrawArgs { first_instance: tile, ..Default::default() });
            draws.levels.push(Vec::new());
            draws.own_vertices.push(Vec::new());
            draws.tile_object.push(oi as u32);
            draws.bbox.push(tile_bbox(t));
        }
    }
}
