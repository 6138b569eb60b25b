//! What a frame is asked for and what it gives back: levels of detail, [`RenderOptions`],
//! [`RenderStats`], [`RenderOutput`].

use crate::cull::{CullOptions, Stat};
use crate::error::{Interrupt, Result};

/// Which level of detail each drawn tile uses.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Lod {
    /// Level 0 (the fine triangles) everywhere: the reference.
    Full,
    /// The coarsest level whose geometric error projects to at most `max_pixel_error` pixels at
    /// the tile's nearest point (`crate::lod::levels`) and whose shading error changes the lit
    /// colour by at most `MAX_SHADING_LEVELS`.
    ScreenError { max_pixel_error: f64 },
}

/// The most a level of detail may change a pixel's lit colour, in 8-bit levels per channel:
/// a level is taken only if its shading error (`crate::lod::shading`, a normal chord) times the
/// object's levels per chord (`lod::shading::shade_levels_per_chord`: its brightest colour, the
/// vertical exaggeration) stays within it. Height fields shade from their fine surface at every
/// level (shading error 0), so only meshes' levels are held back.
pub const MAX_SHADING_LEVELS: f64 = 0.5;

/// [`MAX_SHADING_LEVELS`] for the levels of well tubes (`lod::tube`), whose shading error is
/// mostly their displacement over their radius: the turn of the normal a pixel at the tube's
/// middle sees when the tube moves sideways by the level's whole error, a worst case few of its
/// pixels meet: four 8-bit levels, the 4/255 this project's image comparisons count as visible.
/// Measured on Reek's wells at 1280 x 1024 (9 wells, 8 views at exaggeration 1 to 10, one
/// process): against 2 levels, the wells' triangles fell from 940 k to 402 k over the 8 views and
/// temporal + lod frames by 5 % (geometric mean), while the most differing pixels of any view went
/// from 0.146 to 0.152 % of the image and beyond 4/255 from 0.0075 to 0.0080 %; 8 levels gained 3 %
/// more for 0.23 % differing (`docs/BENCHMARKS.md`).
pub const MAX_TUBE_SHADING_LEVELS: f64 = 4.0;

impl Lod {
    pub fn parse(name: &str, max_pixel_error: f64) -> Result<Self> {
        match name {
            "full" => Ok(Self::Full),
            "screen_error" => {
                crate::error::ensure(max_pixel_error.is_finite() && max_pixel_error > 0.0, "max_pixel_error", || {
                    format!("max_pixel_error is {max_pixel_error}; expected pixels > 0")
                })?;
                Ok(Self::ScreenError { max_pixel_error })
            }
            _ => Err(crate::error::input_err(
                "lod",
                format!("unknown lod {name:?}; expected \"full\" or \"screen_error\""),
            )),
        }
    }
}

/// Which level of detail each block of a reservoir grid uses (`crate::grid`).
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum GridLod {
    /// Level 0 (every boundary face of the active cells).
    Full,
    /// The paper's view-distance ranges (`crate::grid::distance_level`), `alpha` in [8, 15],
    /// `lambda` in [2, 3], the distance taken from the eye to the block's centre.
    Distance { alpha: f64, lambda: f64 },
    /// As `Lod::ScreenError`: the coarsest level whose geometric error projects to at most
    /// `max_pixel_error` pixels at the block's nearest point.
    ScreenError { max_pixel_error: f64 },
}

impl GridLod {
    pub fn parse(name: &str, alpha: f64, lambda: f64, max_pixel_error: f64) -> Result<Self> {
        match name {
            "full" => Ok(Self::Full),
            "distance" => {
                crate::grid::validate_alpha_lambda(alpha, lambda)?;
                Ok(Self::Distance { alpha, lambda })
            }
            "screen_error" => match Lod::parse("screen_error", max_pixel_error)? {
                Lod::ScreenError { max_pixel_error } => Ok(Self::ScreenError { max_pixel_error }),
                Lod::Full => unreachable!("parsed as screen_error"),
            },
            _ => Err(crate::error::input_err(
                "grid_lod",
                format!("unknown grid_lod {name:?}; expected \"full\", \"distance\" or \"screen_error\""),
            )),
        }
    }
}

/// How to render one frame.
#[derive(Clone, Debug)]
pub struct RenderOptions {
    /// A registered strategy's name (`crate::cull::names()`).
    pub culling: String,
    pub cull: CullOptions,
    pub lod: Lod,
    /// The level of detail of reservoir grids' blocks (height fields and meshes follow `lod`).
    pub grid_lod: GridLod,
    /// Polled between the stages of the frame and while waiting for the GPU; when it fires,
    /// `render` returns `Error::Interrupted` and the renderer stays usable (`crate::error::Interrupt`).
    pub interrupt: Interrupt,
}

impl Default for RenderOptions {
    fn default() -> Self {
        Self {
            culling: "none".into(),
            cull: CullOptions::default(),
            lod: Lod::Full,
            grid_lod: GridLod::Full,
            interrupt: Interrupt::default(),
        }
    }
}

impl RenderOptions {
    /// `culling` with the default options.
    pub fn culling(name: &str) -> Self {
        Self { culling: name.into(), ..Default::default() }
    }
}

/// Timings and counts of one frame.
#[derive(Clone, Debug, Default)]
pub struct RenderStats {
    pub triangles_fine_total: u64,
    /// Fine triangles of the tiles drawn by the final pass.
    pub triangles_drawn: u64,
    pub tiles_total: u32,
    pub tiles_drawn: u32,
    /// CPU time of the strategy's `visible_set` (CPU culling, or recording its GPU passes), ms.
    pub cull_ms: f64,
    /// GPU time of the final pass (timestamps; 0 where the adapter has none), ms.
    pub draw_ms: f64,
    /// Wall time from the call to the GPU finishing the frame (no read-back, no untimed
    /// `prepare`), ms.
    pub total_ms: f64,
    /// Wall time to copy the image, depth and counts back and convert them, ms.
    pub readback_ms: f64,
    pub gpu_timestamps: bool,
    /// GPU times of the strategy's passes by name (e.g. "prepass_ms") and the strategy's own
    /// stats (e.g. "nodes_visited").
    pub extra: Vec<(&'static str, Stat)>,
}

impl RenderStats {
    /// A named extra stat, if the frame has it.
    pub fn get(&self, name: &str) -> Option<Stat> {
        self.extra.iter().find(|(n, _)| *n == name).map(|(_, v)| *v)
    }
}

/// The result of one frame, as plain host arrays.
#[derive(Clone, Debug)]
pub struct RenderOutput {
    pub width: u32,
    pub height: u32,
    /// RGBA8, row-major, row 0 = top; the renderer's background where nothing was drawn
    /// (`Renderer::set_background`; opaque black without one).
    pub image: Vec<u8>,
    /// Distance along the view axis (render-space units), +inf where empty.
    pub depth: Vec<f32>,
    /// Per tile: the pixel counts the strategy decided on, in full-image pixels (three_pass: the
    /// pass-2 counts of the coarse proxies; oracle: the unculled image's); for strategies that
    /// count no pixels (none, horizon), the final image's.
    pub tile_pixels: Vec<u32>,
    pub tile_drawn: Vec<bool>,
    pub stats: RenderStats,
    pub near: f64,
    pub far: f64,
    /// The strategy's per-frame arrays by name (horizon: "horizon", one value per column).
    pub arrays: Vec<(&'static str, Vec<f32>)>,
    /// The strategy's per-tile counts by name (three_pass: "box_pixels").
    pub tile_counts: Vec<(&'static str, Vec<u32>)>,
}

impl RenderOutput {
    pub fn array(&self, name: &str) -> Option<&[f32]> {
        self.arrays.iter().find(|(n, _)| *n == name).map(|(_, a)| a.as_slice())
    }
}
