//! Values the lit pass looks up per fragment, appended to the per-sample values
//! (`SceneGeometry::sample_values`), each tile's first word and columns in its grid (`SceneGeometry::tiles`):
//! * the cell values of reservoir grids coloured per cell (`grid::cells`): each tile's table
//!   (`grid::cells::cell_table`);
//! * the logs of well tubes coloured by a log (`lod::tube`): each tile's values by station
//!   (`lod::tube::log_table`), read at the fragment's interpolated station (draw.wgsl
//!   `log_scalar`).

use crate::scene::Scene;

/// Where each tile's table went.
pub(super) struct CellTables {
    /// Per tile (scene order): the table's first word in `sample_values` and the tile's columns
    /// along i and j (a log's: its stations and 1); None for tiles without.
    pub tiles: Vec<Option<[u32; 3]>>,
    /// Per object: some tile of it has a table (its tiles are drawn by `fs_cells`).
    pub objects: Vec<bool>,
    /// Per object: its tables are logs by station.
    pub logs: Vec<bool>,
}

/// A table cell no fine triangle lies in; the lit pass then takes the vertex's value (draw.wgsl).
pub const UNSET: f32 = f32::MAX;

/// Appends the tables of `scene`'s grid tiles and well logs to `words` (scalars through `word`)
/// while they fit `max_words`; a grid whose tables do not fit keeps its colour per face, a well
/// its colour per vertex (and level 0 alone, `SceneGeometry::upload`).
pub(super) fn append(scene: &Scene, words: &mut Vec<f32>, max_words: u64, word: impl Fn(f32) -> f32) -> CellTables {
    let mut tiles = Vec::new();
    let mut objects = Vec::new();
    let mut logs = Vec::new();
    for o in scene.objects() {
        let logged = o.tiles.iter().any(|t| !t.stations.is_empty());
        let tables: Vec<Option<([u32; 3], Vec<f32>)>> = if o.grid().is_some() {
            o.tiles.iter().map(crate::grid::cells::cell_table).collect()
        } else if logged {
            o.tiles.iter().map(crate::lod::tube::log_table).collect()
        } else {
            vec![None; o.tiles.len()]
        };
        let need: u64 = tables.iter().flatten().map(|(_, t)| t.len() as u64).sum();
        let fits = need > 0 && words.len() as u64 + need <= max_words;
        objects.push(fits);
        logs.push(fits && logged);
        for t in tables {
            tiles.push(t.filter(|_| fits).map(|(dims, table)| {
                let first = words.len() as u32;
                words.extend(table.into_iter().map(|x| if x == f32::INFINITY { UNSET } else { word(x) }));
                [first, dims[0], dims[1]]
            }));
        }
    }
    CellTables { tiles, objects, logs }
}
