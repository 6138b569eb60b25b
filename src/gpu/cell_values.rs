//! The cell values of reservoir grids coloured per fragment (`grid::cells`) as the lit pass reads
//! them: each tile's table (`grid::cells::cell_table`) appended to the per-sample values
//! (`SceneGeometry::sample_values`), its first word and columns in the tile's `tile_grid` entry.

use crate::scene::{ObjectKind, Scene};

/// Where each grid tile's table went.
pub(super) struct CellTables {
    /// Per tile (scene order): the table's first word in `sample_values` and the tile's columns
    /// along i and j; None for tiles without.
    pub tiles: Vec<Option<[u32; 3]>>,
    /// Per object: some tile of it has a table (its tiles are drawn by `fs_cells`).
    pub objects: Vec<bool>,
}

/// A table cell no fine triangle lies in; the lit pass then takes the vertex's value (draw.wgsl).
pub const UNSET: f32 = f32::MAX;

/// Appends the tables of `scene`'s grid tiles to `words` (scalars through `word`) while they fit
/// `max_words`; a grid whose tables do not fit keeps its colour per face.
pub(super) fn append(scene: &Scene, words: &mut Vec<f32>, max_words: u64, word: impl Fn(f32) -> f32) -> CellTables {
    let mut tiles = Vec::new();
    let mut objects = Vec::new();
    for o in scene.objects() {
        let tables: Vec<Option<([u32; 3], Vec<f32>)>> = match o.kind {
            ObjectKind::Grid(_) => o.tiles.iter().map(crate::grid::cells::cell_table).collect(),
            _ => vec![None; o.tiles.len()],
        };
        let need: u64 = tables.iter().flatten().map(|(_, t)| t.len() as u64).sum();
        let fits = need > 0 && words.len() as u64 + need <= max_words;
        objects.push(fits);
        for t in tables {
            tiles.push(t.filter(|_| fits).map(|(dims, table)| {
                let first = words.len() as u32;
                words.extend(table.into_iter().map(|x| if x == f32::INFINITY { UNSET } else { word(x) }));
                [first, dims[0], dims[1]]
            }));
        }
    }
    CellTables { tiles, objects }
}
