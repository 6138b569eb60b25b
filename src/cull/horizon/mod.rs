//! Conservative horizon occlusion culling for tiled height fields.
//!
//! Based on the idea of Yalım, "Horizon occlusion culling for real-time rendering of
//! hierarchical terrains": traverse a quadtree over the tiles front to back, keep one
//! horizon value per image column, cull a node whose projected bounding box lies below the
//! horizon in every column it touches, and raise the horizon with the occluders of every
//! tile that is drawn.
//!
//! # What the horizon means
//!
//! `K[c]` (an integer row count, exported as `horizon[c] = K[c]`, or `-inf` when `K[c] == 0`)
//! says: in pixel column `c`, no pixel row `r < K[c]` (rows counted from the bottom, pixel
//! centres at `r + 0.5`) can show a surface point of any node that has not been visited yet.
//! Either the pixel is covered by an already drawn triangle that lies nearer along the pixel's
//! ray than every not-yet-visited node, or no not-yet-visited node's bounding box projects onto
//! that pixel at all ("dead" rows below the remaining nodes, see `dead_rows`).
//!
//! # Occluders (deviation from the paper, on purpose)
//!
//! The paper raises the horizon with segments lying below the tile edges and justifies it with
//! "terrain fills the screen from the bottom up". That argument is not sound with holes (NaN),
//! at the borders of the data, for a pitched camera (vertical lines converge) or near the
//! near plane. Instead, every drawn tile contributes the exact *covered set* of its rendered
//! surface, which is computed from the boundary edges only:
//!
//! * A "good" cell is a grid cell whose 4 corners are finite, so both of its triangles are
//!   drawn whatever the diagonal. The union `P` of the good cells of a tile is a continuous
//!   piecewise-linear surface (disk(s) with holes allowed). Its boundary is the set of cell
//!   sides with a good cell on exactly one side (or on the tile border), oriented
//!   counter-clockwise in world xy. Those edges are precomputed per tile at `build` time
//!   (finest samples, so interior rows/columns of the tile are implicitly used: a tile with
//!   holes still occludes with all of its hole-free part, not just with its border).
//! * Degree theory: if all of `P` lies strictly in front of the eye (and inside the depth
//!   range), the winding number of the projected boundary around a screen point `p` equals
//!   the signed number of points of `P` projecting to `p` (+1 for an up-facing surface seen
//!   from above). Winding `>= 1` therefore proves that the ray through `p` hits an up-facing
//!   (front-facing even if the renderer culls back faces with "up = front") drawn triangle of
//!   this tile inside the clip volume. Per column the winding is evaluated exactly at the
//!   pixel-centre x (half-open crossing rule), so partially covered columns are handled exactly.
//! * Margins for the GPU: a rasterizer snaps vertices to its sub-pixel grid (1/256 px on
//!   lavapipe, >= 1/16 px on any Vulkan device) and computes clip coordinates from f32 positions
//!   with an f32 matrix. A pixel centre is credited only if it is at least `eps` pixels from every
//!   edge of the occluder's boundary (`RASTER_EPS` plus a per-vertex bound of the f32 round-off,
//!   which grows near the eye and with the size of the coordinates; see `View::err_px`; along an
//!   edge it is interpolated between the endpoints' margins, see `add_band`), and occludee boxes
//!   are grown by the largest margin of their corners. Seen through the real renderer, crediting a pixel
//!   0.001 px inside a tile's border edge culled the neighbour tile that the GPU actually gave the
//!   pixel to. Tile seams get no margin: the occluder of a drawn tile is the union of its covered
//!   set with those of its already drawn 8 neighbours (shared sides cancel), and the GPU's shared
//!   vertices make the seam watertight, so a pixel near a seam goes to one of two drawn tiles.
//!   "In the depth range" also keeps an f32 margin, so the GPU never clips a credited cell.
//! * Front-to-back order: children are visited as (eye quadrant, the two adjacent quadrants,
//!   opposite quadrant), decided by which side of the node's two vertical split planes the
//!   centre of projection lies on. For two nodes A visited before B there is always a split
//!   plane with A (and the eye) on one closed side and B on the other, so along every ray every
//!   point of A comes no later than every point of B. Hence a covering point found in A is
//!   nearer than anything in B (ties only exactly on the shared plane, measure zero).
//! * A covered interval `(lo, hi)` in a column only raises `K[c]` if it is contiguous with
//!   the rows already known hidden (`lo` below the centre of row `K[c]`). If it is not, the
//!   dead rows below the lower envelope of all nodes still on the traversal stack (= exactly
//!   the not-yet-visited nodes) are added first, which makes culling work when the camera is
//!   outside the data and the bottom of the screen shows nothing.
//! * Tiles whose bounding box reaches outside the depth range (e.g. the tile under the eye)
//!   use a per-frame mask instead: a cell is good only if its 4 corners are finite AND
//!   inside the depth range (`w > margin`, `0 <= z_clip <= w`); this is evaluated on the fly
//!   for these few tiles only.
//!
//! # Culling test
//!
//! A node is frustum-culled when all 8 box corners are outside one clip plane
//! (`x>w`, `x<-w`, `y>w`, `y<-w`, `z>w`, `z<-w`, `w<=0`; valid for GL and wgpu depth ranges)
//! or when its projected hull contains no pixel centre. Otherwise, if any corner has
//! `w <= margin` the node is kept. Else the projected box hull is evaluated per pixel column
//! (exact upper/lower convex hull of the 8 projected corners at the pixel-centre x) and the
//! node is culled iff every row centre the hull can reach in every column it spans is `< K[c]`.
//! Both kinds of culls are counted in `nodes_culled`.
//!
//! # Depth conventions
//!
//! Standard depth and reverse-Z (the renderer: infinite-far reverse-Z perspective, reverse-Z
//! orthographic, `Greater` test) both work: the clip tests only use `0 <= z <= w` (the wgpu /
//! Vulkan / D3D range, either orientation) and `w > 0`. Front-to-back order comes from the
//! centre of projection (perspective) or the projection direction (orthographic). For
//! orthographic views the direction's sign cannot be read from the matrix (depth grows forward
//! with standard depth, backward with reverse-Z), so `eye` decides: its depth is <= 0 with
//! standard depth and >= 1 with reverse-Z. (Before this rule, reverse-Z orthographic views were
//! traversed back to front and culled visible tiles.)
//!
//! # Validity rule (when `culling_applied == false`)
//!
//! The argument above needs no "eye above terrain", no "no roll" and no particular pitch: it
//! only needs a projective `view_proj` with a centre of projection (perspective) or a
//! projection direction (orthographic), `w > 0` in front, depth monotone along rays (true for
//! any standard or reverse-Z projection), pixel-centre sampling without MSAA, nearest-wins
//! depth test, and full-resolution triangles (two per cell, dropped iff a corner is NaN).
//! Eye below the terrain / looking at the underside: the winding there is negative, so no
//! occluder is credited and the result is conservative (little or no culling).
//! Culling is *disabled* (all non-empty tiles visible, `culling_applied = false`) when:
//! * the grid is invalid (nx<2, ny<2, no tiles, z too short, non-finite or zero spacing),
//!   or width/height is 0 (then every tile, even empty ones, is reported visible for an
//!   invalid grid);
//! * `view_proj` is not finite or degenerate (no centre/direction of projection, or the
//!   forward direction cannot be determined);
//! * the view direction is within 30 degrees of vertical (`|forward.z| > sin 60°`): there a
//!   bottom-up horizon cannot rise (the nadir projects into the screen), so the traversal
//!   would cost time for nothing. This is a usefulness rule, not a correctness one.
//!
//! The centre of projection is derived from `view_proj` itself, so the ordering can never
//! disagree with what is rendered; `eye` (render space, consistent with `view_proj`) is only used
//! for the sign of an orthographic view direction (see "Depth conventions").
//! Not covered: LOD rendering (coarser meshes than the finest samples) - the covered set is
//! computed for the full-resolution surface; MSAA (sub-pixel samples other than the centre).
//!
//! # Files
//!
//! * `view.rs`: `View`, the projection of points, clip tests and the bounds on the
//!   GPU's f32 round-off and sub-pixel snapping (`err_px`, `in_depth`);
//! * `hull.rs`: upper/lower convex chains of a projected box (`Chain`, `hull_chains`);
//! * `tree.rs`: the public types, the quadtree over the tiles (`build`) and the front-to-back
//!   traversal (`cull`, `project_node`, `horizon_culled`, `dead_rows`);
//! * `occluder.rs`: the covered set of a drawn tile (`boundary_edges`, `add_occluder`, `add_band`,
//!   `add_edge`);
//! * `strategy.rs`: the `culling="horizon"` strategy and its tree cache (object-local trees,
//!   offsets applied at cull time, LRU within a byte budget);
//! * `tests.rs`: tests against the CPU reference rasterizer `crate::cull::reference`.

mod hull;
mod occluder;
mod strategy;
#[cfg(test)]
mod tests;
mod tree;
mod view;

pub use strategy::make;
pub use tree::{HeightGrid, HorizonTree};

/// Safety margin in pixels against floating-point round-off (of this module's f64 arithmetic).
const PIX_EPS: f64 = 1e-4;
