//! What an isosurface frame is asked for and what it gives back: [`IsoCulling`], [`IsoWalk`],
//! [`IsoOptions`], [`IsoStats`], [`IsoOutput`].

use crate::error::{input_err, Interrupt, Result};
use crate::iso::march::DEFAULT_CACHE_BUDGET;

/// How the isosurface is culled.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum IsoCulling {
    /// Extract and draw the whole isosurface (the reference).
    None,
    /// Implicit occluders: extract only inside nodes that pass the occlusion-map test.
    Implicit,
    /// For benchmarks: the cells that hold a visible point of the unculled image (rendered
    /// first, untimed, as is reading the cells from its depth), drawn as `Implicit` draws its
    /// marked cells; the same image (see the module docs). About the least any culling that
    /// draws whole cells can draw.
    Oracle,
}

impl IsoCulling {
    pub fn parse(s: &str) -> Result<Self> {
        match s {
            "none" => Ok(Self::None),
            "implicit" => Ok(Self::Implicit),
            "oracle" => Ok(Self::Oracle),
            _ => Err(input_err(
                "culling",
                format!("unknown culling {s:?}; expected \"implicit\", \"none\" or \"oracle\""),
            )),
        }
    }
    pub fn name(self) -> &'static str {
        match self {
            Self::None => "none",
            Self::Implicit => "implicit",
            Self::Oracle => "oracle",
        }
    }
}

/// Where the implicit walk (the occlusion map and the cells seen) runs.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum IsoWalk {
    /// On the host when the adapter is a CPU itself (lavapipe, llvmpipe), else on the GPU.
    Auto,
    /// A compute pass (iso.wgsl `cs_map`), one invocation per pixel.
    Gpu,
    /// On the host's cores (`iso::walk`), one task per image row: the same walk step for step.
    Cpu,
}

impl IsoWalk {
    pub fn parse(s: &str) -> Result<Self> {
        match s {
            "auto" => Ok(Self::Auto),
            "gpu" => Ok(Self::Gpu),
            "cpu" => Ok(Self::Cpu),
            _ => Err(input_err("walk", format!("unknown walk {s:?}; expected \"auto\", \"gpu\" or \"cpu\""))),
        }
    }

    /// Whether the walk runs on the host with adapter `info`.
    pub fn on_host(self, info: &wgpu::AdapterInfo) -> bool {
        match self {
            Self::Auto => info.device_type == wgpu::DeviceType::Cpu,
            Self::Gpu => false,
            Self::Cpu => true,
        }
    }
}

/// Options of one isosurface frame.
#[derive(Clone, Debug)]
pub struct IsoOptions {
    pub culling: IsoCulling,
    /// Depth of the occluder nodes (root = 0); `None` = `max_depth` (single cells: the class grid
    /// costs 4 bits per cell and the walk little more than at coarser depths).
    pub occluder_depth: Option<u32>,
    /// Depth of the nodes tested and extracted (root = 0); `None` = `max_depth - 2` (a lazy
    /// volume's: `max_depth - 3`, the octree's finest stored depth, whose nodes need no sample).
    pub cull_depth: Option<u32>,
    /// Surface colour, RGB in [0, 1].
    pub color: [f32; 3],
    /// Reuse (and fill) the per-node patch cache. `false` extracts every visible node afresh.
    pub use_cache: bool,
    /// Also read back the occlusion map (as linear depth).
    pub return_map: bool,
    /// Memory budget of the renderer's isosurface caches in bytes (patches, and at most a quarter
    /// of it for the straddling-node lists); least recently used entries are dropped beyond it.
    pub cache_budget: usize,
    /// Let the walk jump whole skip bricks of one class (see the module docs); `false` walks cell
    /// by cell. Both give the same map, counts of drawn cells and image.
    pub space_skipping: bool,
    /// With single-cell occluders, let the walk place the contour of every face it crosses and stop
    /// right behind the surface (module docs, "Contours"): `Some(true)` always, `Some(false)` never
    /// (it knows only uniform faces), `None` (default) always for the host's walk ([`IsoWalk`]),
    /// and for the compute walk where the surface is dense: where the nodes of 4³ cells that
    /// straddle the isovalue are at least `super::CONTOUR_MIN_DENSITY` of them. All give the unculled
    /// image; contours draw fewer triangles.
    pub face_contours: Option<bool>,
    /// Where the walk runs (`IsoWalk::Auto`: on the host when the adapter is a CPU). Both walks
    /// give the unculled image, and the same map and cells seen with the same `face_contours`
    /// choice (by default the host's also places contours on sparse surfaces: fewer cells).
    pub walk: IsoWalk,
    /// Polled between the stages of the frame (map, each level of node tests, extraction); when
    /// it fires, `render` returns `Error::Interrupted` and the caches stay valid.
    pub interrupt: Interrupt,
}

impl Default for IsoOptions {
    fn default() -> Self {
        Self {
            culling: IsoCulling::Implicit,
            occluder_depth: None,
            cull_depth: None,
            color: [0.85, 0.72, 0.45],
            use_cache: true,
            return_map: false,
            cache_budget: DEFAULT_CACHE_BUDGET,
            space_skipping: true,
            face_contours: None,
            walk: IsoWalk::Auto,
            interrupt: Interrupt::default(),
        }
    }
}

/// Counts and wall-clock times (milliseconds) of one isosurface frame.
#[derive(Clone, Debug, Default)]
pub struct IsoStats {
    pub surface_triangles: u64,
    pub surface_vertices: u64,
    /// Nodes tested against the occlusion map, all levels together.
    pub nodes_tested: u32,
    /// Nodes tested at the cull depth itself.
    pub nodes_tested_cull_depth: u32,
    /// Visible nodes at the cull depth (all straddling nodes for culling = none).
    pub nodes_visible: u32,
    /// Straddling nodes at the cull depth (what culling = none extracts).
    pub nodes_straddling: u32,
    /// Below / Above nodes at the occluder depth (the map's class grid).
    pub occluder_boxes_below: u32,
    pub occluder_boxes_above: u32,
    pub occluder_depth: u32,
    pub cull_depth: u32,
    pub max_depth: u32,
    /// Patches found in the cache / extracted this frame.
    pub patches_cached: u32,
    pub patches_extracted: u32,
    /// Nodes at the occluder depth with a NaN sample or touching one (never occluders; they stop
    /// the map's walk, `bricks::dilate_nan`).
    pub occluder_nodes_nan: u32,
    /// The class grid (first frame of an isovalue and occluder depth, else 0) and the recording of
    /// the map pass, on the CPU; the pass itself runs on the GPU with the first node test and is
    /// part of `cull_ms` (one submission).
    pub occluder_ms: f64,
    /// Occlusion map and node test (one GPU walk per pixel), read-back included.
    pub cull_ms: f64,
    /// Marching cubes (cache look-ups included).
    pub extract_ms: f64,
    /// Upload of what is not on the GPU yet (the pool's new patches; implicit culling: the kept
    /// cells' indices) and the lit draw (GPU finished).
    pub draw_ms: f64,
    /// extract_ms + draw_ms.
    pub surface_ms: f64,
    /// Whole frame, from the call to the GPU finishing the image (no read-back, no setup).
    pub total_ms: f64,
    /// One-time work this frame paid for before its clock started (not in `total_ms`): pipeline
    /// creation and the case table (the renderer's first isosurface frame), targets (first frame
    /// at a size). 0 on other frames.
    pub setup_ms: f64,
    /// Queue submissions and GPU-to-host read-backs inside the frame (the walk's marked cells; the
    /// image read-back after the frame is not counted).
    pub submissions: u32,
    pub readbacks: u32,
    pub readback_ms: f64,
    /// Bytes held by the renderer's isosurface caches after the frame (patches and straddling-node
    /// lists), at most `IsoOptions::cache_budget`.
    pub cache_bytes: u64,
    /// Bytes of the cached patches' copy kept on the GPU between frames (vertices and triangles;
    /// at most about twice those the cache holds).
    pub gpu_cache_bytes: u64,
    /// Bytes of the walk's contour bricks kept with the class grid, on the GPU or on the host
    /// where the walk runs (single-cell occluders: one word per brick of 4³ cells, 125 samples per
    /// brick that holds surface; 0 without them: no implicit frame yet, coarser occluders, or, on
    /// the GPU, more than one storage binding).
    pub contour_bytes: u64,
    /// Where this frame's walk ran: `Some(true)` on the host, `Some(false)` on the GPU, `None`
    /// without one (culling = none).
    pub walk_on_host: Option<bool>,
    /// The host's walk: the pixel rays that entered the volume's box and the steps they took (a
    /// cell entered or a jump across skippable bricks: `walk::WalkCounts`). 0 where the walk ran on
    /// the GPU (not counted there) or there was none.
    pub walk_rays: u64,
    pub walk_steps: u64,
    /// Bytes this frame read from a lazy volume's sample store (brick-cache misses; 0 for a volume
    /// in memory), and the bytes its brick cache holds after the frame (`iso::store`).
    pub bytes_read: u64,
    pub brick_cache_bytes: u64,
}

/// One rendered isosurface frame as host arrays.
#[derive(Clone, Debug)]
pub struct IsoOutput {
    pub width: u32,
    pub height: u32,
    /// RGBA8, row-major, row 0 = top; opaque black where empty (`Renderer::render_isosurface`
    /// puts its background there).
    pub image: Vec<u8>,
    /// Distance along the view axis (render-space units), +inf where empty.
    pub depth: Vec<f32>,
    /// The straddling nodes at the cull depth, `[depth, ix, iy, iz]`, in octree order.
    pub nodes: Vec<[u32; 4]>,
    /// Per node of `nodes`: its march cells that may hold surface and that some pixel's ray
    /// entered before the occlusion map (0 when hidden, and for culling = none).
    pub node_pixels: Vec<u32>,
    /// Per node of `nodes`: extracted and drawn.
    pub node_drawn: Vec<bool>,
    /// The occlusion map as linear depth (+inf where nothing is proven), when asked for.
    pub map: Option<Vec<f32>>,
    pub stats: IsoStats,
    pub near: f64,
    pub far: f64,
}
