//! Level 0 of a block: the boundary faces of its active cells, split on faults so that the drawn
//! surface of each region is watertight.
//!
//! # Faces and pieces
//!
//! A cell's lateral faces lie between two pillars. On one *interface* (the pillar pair shared by
//! two neighbouring columns) every face of either column is, in the interface's own 2-D frame
//! (t in [0, 1] from one pillar to the other, s = the height along the pillars, `up * z`), the
//! region between two lines that span the whole interface: its top edge and its bottom edge. When
//! the two columns' faces coincide layer by layer (no fault; checked on the corners themselves)
//! each face is whole: drawn unless the cell across is active, of the same region. Otherwise
//! (a fault) each face is cut into *pieces*: its intersection with every active cell across
//! (drawn unless that cell has the same region: the overlap is then interior) and its
//! intersections with the gaps between them (exposed: drawn). Every piece is convex (a face
//! intersected with a strip between two lines) and computed symmetrically from the same lines
//! on both sides: its vertices are the points where two of the lines cross or meet a pillar, each
//! computed by one canonical formula (the pair of lines ordered, the point interpolated along the
//! first), so the piece of A over B and the piece of B over A have the same vertices, bit for bit.
//!
//! # Why the result is watertight
//!
//! Within one region, an edge of the drawn surface lies either on a pillar, or on one of the lines
//! of an interface (a cell's top or bottom edge), or inside a face (triangulation; shared by
//! construction). Along a pillar, every drawn face's edge is split at every corner height of the
//! active cells of the (up to four) columns around it (the pillar's *breakpoints*), so two faces
//! meeting along a pillar share the same sub-segments. Along a line of an interface, the vertices
//! are the line's crossings with the other column's lines: the pieces on either side of the line
//! have exactly those (where a line crosses it, the pieces on both sides change), and the top or
//! bottom face whose edge it is inserts the same crossings into that edge. Faces interior to a
//! region (across active cells of the same region, layer-to-layer faces that share all four
//! corners) are never built; the overlaps across a fault within one region are interior pieces.
//! What is left is the boundary of the union of the region's cells, closed. This holds for
//! pillar grids whose cells are not inverted (top at or above bottom on every pillar) and do not
//! overlap within a column; other input is drawn the same way, without the guarantee, and never
//! panics. Places where two cells of a region touch along an edge only are non-manifold by
//! nature (four faces meet there).
//!
//! Collapsed cells (top corner = bottom corner on all four pillars: zero volume) are skipped
//! altogether, active or not: they draw nothing and a layer above and a layer below them face
//! each other directly. Zero-area faces (a pinched side) are not emitted.

use super::poly::{clean, hull, triangulate, zero_area, FastMap, Verts, NO_PILLAR};
use super::Ctx;

/// One face of level 0 or of a merged level: a convex polygon of vertex ids in outward order.
pub(crate) struct Face {
    pub verts: Vec<u32>,
    /// Triangles (vertex ids), computed once.
    pub tris: Vec<[u32; 3]>,
    /// 0 = -i, 1 = +i, 2 = -j, 3 = +j, 4 = top, 5 = bottom.
    pub dir: u8,
    pub k: u32,
    /// The cell's column (global), or a merged face's first column.
    pub ci: u32,
    pub cj: u32,
    pub region: i32,
    pub value: f64,
    /// The whole side of its cell (or merged node), not a piece of it: only whole faces merge.
    pub whole: bool,
    /// Half the cell's size across the face (thickness for top/bottom, length along i or j for
    /// lateral faces): merging may move the surface by at most this.
    pub tol: f64,
    /// What lies across the face ([`kind`]); a merged face has its first member's.
    pub kind: u8,
    /// Cell coordinates ([`super::cells`]) of `verts`, then of the triangles' other vertices;
    /// empty unless the grid colours by cell values.
    pub lat: Vec<u32>,
}

/// What lies across a face.
///
/// Interior ([`kind::interior`]) are the faces between two regions (a region boundary, or a fault
/// piece over a cell of another region: each region's surface is closed, so both regions draw the
/// face, back to back) and the faces of a *cavity*: an inactive cell whose six neighbours are
/// present cells (of any regions) that share its corners (so the void is enclosed by them).
/// From any point outside every cell, a ray to such a face crosses the boundary of the union of
/// the cells first, and that boundary is drawn (faces facing nothing, holes open to the outside,
/// fault pieces over gaps): a level's index list draws its interior faces last, and frames leave
/// them out while the grid's box lies wholly beyond the near plane. At level 0 this is exact; merged levels move
/// the regions' surfaces apart by at most the level's error, so a sliver between two regions may
/// show what lies behind instead of the interior face. A merged face is interior only when all
/// its faces are of one interior kind.
pub(crate) mod kind {
    /// Nothing: the grid's outline.
    pub const OUTER: u8 = 0;
    /// An inactive or collapsed cell inside the grid (not a cavity).
    pub const HOLE: u8 = 1;
    /// A cell of another region with the same corners (an unfaulted region boundary).
    pub const REGION: u8 = 2;
    /// A piece of a faulted face over a cell of another region.
    pub const FAULT_REGION: u8 = 3;
    /// A piece of a faulted face over a gap between the cells across (or beyond them).
    pub const FAULT_GAP: u8 = 4;
    /// A top or bottom face whose neighbour in the column (same region) has other corners.
    pub const MISMATCH: u8 = 5;
    /// An inactive cell enclosed by present cells (see the module).
    pub const CAVITY: u8 = 6;
    /// A merged face of faces of different kinds.
    pub const MIXED: u8 = 7;
    pub const NAMES: [&str; 8] =
        ["outer", "hole", "region", "fault-region", "fault-gap", "mismatch", "cavity", "mixed"];

    /// Hidden from any point outside the grid's cells (see the module).
    pub fn interior(kind: u8) -> bool {
        matches!(kind, REGION | FAULT_REGION | CAVITY)
    }
}

/// A block's columns `i0..i1` x `j0..j1`.
#[derive(Clone, Copy)]
pub(crate) struct Block {
    pub i0: usize,
    pub i1: usize,
    pub j0: usize,
    pub j1: usize,
}

impl Block {
    /// Pillar column `pi` is a seam with a neighbouring block (of a grid `ni` cells wide).
    pub fn seam_i(&self, pi: usize, ni: usize) -> bool {
        (pi == self.i0 && self.i0 > 0) || (pi == self.i1 && self.i1 < ni)
    }
    pub fn seam_j(&self, pj: usize, nj: usize) -> bool {
        (pj == self.j0 && self.j0 > 0) || (pj == self.j1 && self.j1 < nj)
    }
}

/// A line of an interface: heights at t = 0 and t = 1 and the end points.
#[derive(Clone, Copy)]
struct Line {
    s0: f64,
    s1: f64,
    p0: [f64; 3],
    p1: [f64; 3],
}

impl Line {
    #[inline]
    fn at(&self, t: f64) -> f64 {
        self.s0 + t * (self.s1 - self.s0)
    }
    fn key(&self) -> (u64, u64) {
        (self.s0.to_bits(), self.s1.to_bits())
    }
    fn same(&self, o: &Line) -> bool {
        self.s0 == o.s0 && self.s1 == o.s1
    }
}

/// Where two lines cross strictly inside the interface: (t, position), the same for either order.
fn crossing(l: &Line, m: &Line) -> Option<(f64, [f64; 3])> {
    let (a, b) = if l.key() <= m.key() { (l, m) } else { (m, l) };
    let (d0, d1) = (a.s0 - b.s0, a.s1 - b.s1);
    if !((d0 > 0.0 && d1 < 0.0) || (d0 < 0.0 && d1 > 0.0)) {
        return None;
    }
    let t = d0 / (d0 - d1);
    let p = [0, 1, 2].map(|x| a.p0[x] + t * (a.p1[x] - a.p0[x]));
    Some((t, p))
}

/// One present cell of one side of an interface.
#[derive(Clone, Copy)]
struct SideCell {
    k: usize,
    cell: usize,
    top: Line,
    bot: Line,
}

/// One side of an interface as [`Level0::interface`] draws it: its faces' direction, whether
/// their (t, s) outlines are reversed, its column and the one across, the interface's pillars
/// (at t = 0 and t = 1) and whether they lie on a seam.
#[derive(Clone, Copy)]
struct Side {
    dir: u8,
    rev: bool,
    col: (usize, usize),
    other_col: Option<(usize, usize)>,
    pillars: ((usize, usize), (usize, usize)),
    on_border: bool,
}

/// A pillar's breakpoints: (height s, position), sorted by s.
type Breakpoints = Vec<(f64, [f64; 3])>;

/// The level-0 builder of one block.
pub(crate) struct Level0<'c, 'a> {
    pub ctx: &'c Ctx<'a>,
    pub b: Block,
    pub verts: Verts,
    pub faces: Vec<Face>,
    /// Pillar breakpoints (s, position), sorted by s, built on first use; index local pillar.
    pillars: Vec<Option<Breakpoints>>,
    /// Crossings on the edges of top/bottom faces: (cell, side 0..4, 0 = top / 1 = bottom) ->
    /// vertex ids in order of increasing t along that side's interface.
    cross: FastMap<(usize, u8, u8), Vec<u32>>,
}

impl<'c, 'a> Level0<'c, 'a> {
    pub fn new(ctx: &'c Ctx<'a>, b: Block) -> Self {
        let np = (b.i1 - b.i0 + 1) * (b.j1 - b.j0 + 1);
        Self {
            ctx,
            b,
            verts: Verts::new(ctx.origin),
            faces: Vec::new(),
            pillars: vec![None; np],
            cross: FastMap::default(),
        }
    }

    /// Whether a pillar lies on a seam with another block (the grid's own outline is not a seam:
    /// no neighbour has to meet it, so it merges like the inside).
    fn pillar_border(&self, pi: usize, pj: usize) -> bool {
        self.b.seam_i(pi, self.ctx.g.ni) || self.b.seam_j(pj, self.ctx.g.nj)
    }

    fn pillar_id(&self, pi: usize, pj: usize) -> u32 {
        (pj * (self.ctx.g.ni + 1) + pi) as u32
    }

    /// The breakpoints of pillar (pi, pj): every corner height of the present cells of the
    /// columns around it, in a fixed order (so every block computes the same table).
    fn pillar(&mut self, pi: usize, pj: usize) -> &[(f64, [f64; 3])] {
        let b = self.b;
        let slot = (pj - b.j0) * (b.i1 - b.i0 + 1) + (pi - b.i0);
        if self.pillars[slot].is_none() {
            let g = self.ctx.g;
            let mut v: Vec<(f64, [f64; 3])> = Vec::new();
            for cj in pj.saturating_sub(1)..=pj.min(g.nj - 1) {
                for ci in pi.saturating_sub(1)..=pi.min(g.ni - 1) {
                    let c = (pi - ci) | ((pj - cj) << 1);
                    for k in 0..g.nk {
                        let cell = self.ctx.cell(k, cj, ci);
                        if self.ctx.present(cell) {
                            for cc in [c, c | 4] {
                                let p = self.ctx.corner(cell, cc);
                                v.push((self.ctx.s(p), p));
                            }
                        }
                    }
                }
            }
            v.sort_by(|a, b| a.0.total_cmp(&b.0));
            v.dedup_by(|a, b| a.0 == b.0);
            self.pillars[slot] = Some(v);
        }
        self.pillars[slot].as_deref().unwrap_or(&[])
    }

    /// The vertex on pillar (pi, pj) at height s (from the pillar's table; `fallback` if absent).
    fn pillar_vertex(&mut self, pi: usize, pj: usize, s: f64, fallback: [f64; 3], region: i32) -> u32 {
        let tab = self.pillar(pi, pj);
        let p = match tab.binary_search_by(|e| e.0.total_cmp(&s)) {
            Ok(x) => tab[x].1,
            Err(_) => fallback,
        };
        let (border, id) = (self.pillar_border(pi, pj), self.pillar_id(pi, pj));
        self.verts.get(p, region, border, id)
    }

    /// Breakpoints of pillar (pi, pj) strictly between heights a and b, in order from a to b.
    fn breakpoints(&mut self, pi: usize, pj: usize, a: f64, b: f64, region: i32, out: &mut Vec<u32>) {
        let (lo, hi) = (a.min(b), a.max(b));
        let tab = self.pillar(pi, pj);
        let start = tab.partition_point(|e| e.0 <= lo);
        let end = tab.partition_point(|e| e.0 < hi);
        if start >= end {
            return;
        }
        let pts: Vec<[f64; 3]> = tab[start..end].iter().map(|e| e.1).collect();
        let (border, id) = (self.pillar_border(pi, pj), self.pillar_id(pi, pj));
        let first = out.len();
        for p in pts {
            out.push(self.verts.get(p, region, border, id));
        }
        if a > b {
            out[first..].reverse();
        }
    }

    /// Pushes a face (dropping zero-area ones); `poly` in outward order.
    #[allow(clippy::too_many_arguments)]
    fn push(
        &mut self,
        poly: &[u32],
        (dir, kind): (u8, u8),
        k: usize,
        cell_col: (usize, usize),
        cell: usize,
        whole: bool,
        tol: f64,
    ) {
        let Some(poly) = clean(poly) else { return };
        if zero_area(&poly, &self.verts) {
            return;
        }
        let region = self.ctx.region(cell);
        let mut tris = Vec::with_capacity(poly.len());
        triangulate(&poly, &mut self.verts, region, &mut tris);
        self.faces.push(Face {
            verts: poly,
            tris,
            dir,
            k: k as u32,
            ci: cell_col.1 as u32,
            cj: cell_col.0 as u32,
            region,
            value: self.ctx.value(cell),
            whole,
            tol,
            kind,
            lat: Vec::new(),
        });
    }

    /// Builds every face of the block.
    pub fn build(&mut self) {
        let b = self.b;
        for j in b.j0..b.j1 {
            for pi in b.i0..=b.i1 {
                self.interface(false, pi, j);
            }
        }
        for pj in b.j0..=b.j1 {
            for i in b.i0..b.i1 {
                self.interface(true, i, pj);
            }
        }
        for j in b.j0..b.j1 {
            for i in b.i0..b.i1 {
                self.column_k_faces(j, i);
            }
        }
    }

    /// The faces of this block's cells on one interface. `jface` false: the i-interface at pillar
    /// column `a` = pi, row `bb` = j, between columns (j, pi - 1) and (j, pi), pillars (pi, j) at
    /// t = 0 and (pi, j + 1) at t = 1. `jface` true: the j-interface of column `a` = i at pillar
    /// row `bb` = pj, between columns (pj - 1, i) and (pj, i), pillars (i, pj) and (i + 1, pj).
    fn interface(&mut self, jface: bool, a: usize, bb: usize) {
        let g = self.ctx.g;
        let blk = self.b;
        // (pillar at t=0, pillar at t=1), the two columns (j, i) if they exist, and the corner
        // indices (top t0, top t1, bottom t0, bottom t1) of each side's face.
        let (p0, p1, lo, hi, on_border) = if !jface {
            let (pi, j) = (a, bb);
            let lo = (pi >= 1).then(|| (j, pi - 1));
            let hi = (pi < g.ni).then_some((j, pi));
            ((pi, j), (pi, j + 1), lo, hi, blk.seam_i(pi, g.ni))
        } else {
            let (i, pj) = (a, bb);
            let lo = (pj >= 1).then(|| (pj - 1, i));
            let hi = (pj < g.nj).then_some((pj, i));
            ((i, pj), (i + 1, pj), lo, hi, blk.seam_j(pj, g.nj))
        };
        let (lo_c, hi_c): ([usize; 4], [usize; 4]) =
            if !jface { ([1, 3, 5, 7], [0, 2, 4, 6]) } else { ([2, 3, 6, 7], [0, 1, 4, 5]) };
        // Face directions and whether a counter-clockwise (t, s) outline must be reversed.
        let flip = self.ctx.flip;
        let (lo_dir, hi_dir, lo_rev, hi_rev) = if !jface { (1u8, 0u8, flip, !flip) } else { (3u8, 2u8, !flip, flip) };
        let in_block = |c: Option<(usize, usize)>| {
            c.is_some_and(|(j, i)| (blk.i0..blk.i1).contains(&i) && (blk.j0..blk.j1).contains(&j))
        };
        let (lo_in, hi_in) = (in_block(lo), in_block(hi));
        if !lo_in && !hi_in {
            return;
        }
        let ctx = self.ctx;
        let side_cells = |col: Option<(usize, usize)>, cs: [usize; 4]| -> Vec<SideCell> {
            let Some((j, i)) = col else { return Vec::new() };
            (0..g.nk)
                .filter_map(|k| {
                    let cell = ctx.cell(k, j, i);
                    ctx.present(cell).then(|| {
                        let q = cs.map(|c| ctx.corner(cell, c));
                        let top = Line { s0: ctx.s(q[0]), s1: ctx.s(q[1]), p0: q[0], p1: q[1] };
                        let bot = Line { s0: ctx.s(q[2]), s1: ctx.s(q[3]), p0: q[2], p1: q[3] };
                        SideCell { k, cell, top, bot }
                    })
                })
                .collect()
        };
        // Unfaulted: every layer's two faces have the same corners (or one column is missing).
        let faulted = match (lo, hi) {
            (Some((j0, i0)), Some((j1, i1))) => (0..g.nk).any(|k| {
                let (ca, cb) = (ctx.cell(k, j0, i0), ctx.cell(k, j1, i1));
                (ctx.present(ca) || ctx.present(cb))
                    && (0..4).any(|x| ctx.corner(ca, lo_c[x]) != ctx.corner(cb, hi_c[x]))
            }),
            _ => false,
        };
        let lo_cells = side_cells(lo, lo_c);
        let hi_cells = side_cells(hi, hi_c);
        let tol_of = |cell: usize| -> f64 {
            // Half the cell's length across the face (between its two faces on this axis).
            let (ca, cb) = if !jface { ([0usize, 2, 4, 6], [1usize, 3, 5, 7]) } else { ([0, 1, 4, 5], [2, 3, 6, 7]) };
            let mut s = 0.0;
            for x in 0..4 {
                let (p, q) = (ctx.corner(cell, ca[x]), ctx.corner(cell, cb[x]));
                s += ((p[0] - q[0]).powi(2) + (p[1] - q[1]).powi(2) + (p[2] - q[2]).powi(2)).sqrt();
            }
            s / 8.0
        };
        for (own, other, col, dir, rev, inb) in
            [(&lo_cells, &hi_cells, lo, lo_dir, lo_rev, lo_in), (&hi_cells, &lo_cells, hi, hi_dir, hi_rev, hi_in)]
        {
            if !inb {
                continue;
            }
            let Some(col) = col else { continue };
            let other_col = if dir == lo_dir { hi } else { lo };
            let side = Side { dir, rev, col, other_col, pillars: (p0, p1), on_border };
            for a in own.iter() {
                let region = ctx.region(a.cell);
                let tol = tol_of(a.cell);
                if !faulted {
                    self.unfaulted_face(a, side, region, tol);
                } else {
                    self.faulted_pieces(a, other, side, region, tol);
                }
            }
        }
    }

    /// The face of cell `a` on an unfaulted interface (none where the cell across is present and
    /// of the same region: interior), its corners and the pillars' breakpoints between them.
    fn unfaulted_face(&mut self, a: &SideCell, side: Side, region: i32, tol: f64) {
        let ctx = self.ctx;
        let Side { dir, rev, col, other_col, pillars: (p0, p1), .. } = side;
        let across = other_col.map(|(j, i)| ctx.cell(a.k, j, i));
        let interior = across.is_some_and(|c| ctx.present(c) && ctx.region(c) == region);
        if interior {
            return;
        }
        let fk = match across {
            None => kind::OUTER,
            Some(c) if ctx.present(c) => kind::REGION,
            Some(c) if ctx.enclosed(c) => kind::CAVITY,
            Some(_) => kind::HOLE,
        };
        // Counter-clockwise in (t, s): bottom t0 -> bottom t1 -> top t1 -> top t0.
        let mut poly = Vec::with_capacity(4);
        let bp = |s: &mut Self, p: [f64; 3], pil: (usize, usize)| {
            let (b, id) = (s.pillar_border(pil.0, pil.1), s.pillar_id(pil.0, pil.1));
            s.verts.get(p, region, b, id)
        };
        poly.push(bp(self, a.bot.p0, p0));
        poly.push(bp(self, a.bot.p1, p1));
        self.breakpoints(p1.0, p1.1, a.bot.s1, a.top.s1, region, &mut poly);
        poly.push(bp(self, a.top.p1, p1));
        poly.push(bp(self, a.top.p0, p0));
        self.breakpoints(p0.0, p0.1, a.top.s0, a.bot.s0, region, &mut poly);
        if rev {
            poly.reverse();
        }
        self.push(&poly, (dir, fk), a.k, col, a.cell, true, tol);
    }

    /// The pieces of cell `a`'s face on a faulted interface against the cells across (`other`):
    /// first the crossings of its top and bottom with their lines (for its top and bottom faces),
    /// then a piece per cell across of another region, per gap, and above the last.
    fn faulted_pieces(&mut self, a: &SideCell, other: &[SideCell], side: Side, region: i32, tol: f64) {
        let ctx = self.ctx;
        let Side { dir, rev, col, other_col, pillars: (p0, p1), on_border } = side;
        // Faulted: the crossings of this cell's top and bottom with the other side's lines
        // (for its top/bottom faces), then the pieces.
        for (tb, l) in [(0u8, a.top), (1u8, a.bot)] {
            let mut xs: Vec<(f64, u32)> = Vec::new();
            for o in other.iter() {
                for m in [o.top, o.bot] {
                    if let Some((t, p)) = crossing(&l, &m) {
                        xs.push((t, self.verts.get(p, region, on_border, NO_PILLAR)));
                    }
                }
            }
            if !xs.is_empty() {
                xs.sort_by(|x, y| x.0.total_cmp(&y.0));
                let mut ids: Vec<u32> = xs.iter().map(|x| x.1).collect();
                ids.dedup();
                self.cross.insert((a.cell, dir, tb), ids);
            }
        }
        let range = |c: &SideCell| (c.bot.s0.min(c.bot.s1), c.top.s0.max(c.top.s1));
        let (alo, ahi) = range(a);
        let mut prev: Option<&SideCell> = None;
        for o in other.iter() {
            let (olo, ohi) = range(o);
            if olo < ahi && ohi > alo {
                let drawn = ctx.region(o.cell) != region;
                if drawn {
                    self.piece(
                        a,
                        Some(o.bot),
                        Some(o.top),
                        (p0, p1),
                        on_border,
                        (dir, rev, col, tol, false, kind::FAULT_REGION),
                    );
                }
            }
            // The gap above o (below prev).
            let how = (dir, rev, col, tol, false, kind::FAULT_GAP);
            self.piece(a, Some(o.top), prev.map(|p| p.bot), (p0, p1), on_border, how);
            prev = Some(o);
        }
        let whole = other.is_empty();
        let fk = match (whole, other_col) {
            (false, _) => kind::FAULT_GAP,
            (true, None) => kind::OUTER,
            (true, Some(_)) => kind::HOLE,
        };
        self.piece(a, None, prev.map(|p| p.bot), (p0, p1), on_border, (dir, rev, col, tol, whole, fk));
    }

    /// The piece of cell `a`'s face between lines `lo` and `hi` (None = unbounded), if it has an
    /// area; `how` = (dir, reverse, column, tol, whole, kind).
    #[allow(clippy::too_many_arguments)]
    fn piece(
        &mut self,
        a: &SideCell,
        lo: Option<Line>,
        hi: Option<Line>,
        pil: ((usize, usize), (usize, usize)),
        on_border: bool,
        how: (u8, bool, (usize, usize), f64, bool, u8),
    ) {
        let (dir, rev, col, tol, whole, fk) = how;
        if let (Some(l), Some(h)) = (lo, hi) {
            if l.same(&h) || (h.s0 <= l.s0 && h.s1 <= l.s1) {
                return;
            }
        }
        if let Some(l) = lo {
            if l.s0 >= a.top.s0.max(a.top.s1) && l.s1 >= a.top.s0.max(a.top.s1) {
                return;
            }
        }
        if let Some(h) = hi {
            if h.s0 <= a.bot.s0.min(a.bot.s1) && h.s1 <= a.bot.s0.min(a.bot.s1) {
                return;
            }
        }
        let region = self.ctx.region(a.cell);
        let lines: Vec<Line> = [Some(a.top), Some(a.bot), lo, hi].into_iter().flatten().collect();
        let scale = lines.iter().fold(1.0f64, |m, l| m.max(l.s0.abs()).max(l.s1.abs()));
        let e = 1e-9 * scale;
        let inside = |t: f64, s: f64| {
            s >= a.bot.at(t) - e
                && s <= a.top.at(t) + e
                && lo.is_none_or(|l| s >= l.at(t) - e)
                && hi.is_none_or(|h| s <= h.at(t) + e)
        };
        let mut pts: Vec<(f64, f64, u32)> = Vec::with_capacity(8);
        for l in &lines {
            for (t, s, p, pp) in [(0.0, l.s0, l.p0, pil.0), (1.0, l.s1, l.p1, pil.1)] {
                if inside(t, s) {
                    let v = self.pillar_vertex(pp.0, pp.1, s, p, region);
                    pts.push((t, s, v));
                }
            }
        }
        for x in 0..lines.len() {
            for y in x + 1..lines.len() {
                if let Some((t, p)) = crossing(&lines[x], &lines[y]) {
                    let s = self.ctx.s(p);
                    if inside(t, s) {
                        pts.push((t, s, self.verts.get(p, region, on_border, NO_PILLAR)));
                    }
                }
            }
        }
        let h = hull(pts);
        if h.len() < 3 {
            return;
        }
        // Outline with the pillar breakpoints inserted on the sides along the pillars.
        let mut poly: Vec<u32> = Vec::with_capacity(h.len() + 4);
        for w in 0..h.len() {
            let (a0, a1) = (h[w], h[(w + 1) % h.len()]);
            poly.push(a0.2);
            if a0.0 == a1.0 && (a0.0 == 0.0 || a0.0 == 1.0) {
                let pp = if a0.0 == 0.0 { pil.0 } else { pil.1 };
                self.breakpoints(pp.0, pp.1, a0.1, a1.1, region, &mut poly);
            }
        }
        if rev {
            poly.reverse();
        }
        self.push(&poly, (dir, fk), a.k, col, a.cell, whole, tol);
    }

    /// Top and bottom faces of column (j, i).
    fn column_k_faces(&mut self, j: usize, i: usize) {
        let ctx = self.ctx;
        let g = ctx.g;
        for k in 0..g.nk {
            let cell = ctx.cell(k, j, i);
            if !ctx.present(cell) {
                continue;
            }
            let region = ctx.region(cell);
            let tol = 0.5 * ctx.thickness(cell);
            for (tb, up) in [(0u8, true), (1u8, false)] {
                // The next cell above (below) that is not collapsed.
                let mut nb = None;
                let mut kk = k;
                loop {
                    if up {
                        if kk == 0 {
                            break;
                        }
                        kk -= 1;
                    } else {
                        kk += 1;
                        if kk >= g.nk {
                            break;
                        }
                    }
                    let c = ctx.cell(kk, j, i);
                    if !ctx.collapsed(c) {
                        nb = Some(c);
                        break;
                    }
                }
                let (mine, theirs) = if up { (0, 4) } else { (4, 0) };
                let interior = nb.is_some_and(|c| {
                    ctx.present(c)
                        && ctx.region(c) == region
                        && (0..4).all(|x| ctx.corner(c, theirs + x) == ctx.corner(cell, mine + x))
                });
                if interior {
                    continue;
                }
                let fk = match nb {
                    None => kind::OUTER,
                    Some(c) if !ctx.present(c) && ctx.enclosed(c) => kind::CAVITY,
                    Some(c) if !ctx.present(c) => kind::HOLE,
                    Some(c) if ctx.region(c) != region => kind::REGION,
                    Some(_) => kind::MISMATCH,
                };
                // Outline: top c0 -(-j)-> c1 -(+i)-> c3 -(+j)-> c2 -(-i)-> c0;
                // bottom c4 -(-i)-> c6 -(+j)-> c7 -(+i)-> c5 -(-j)-> c4. (side, forward in t?)
                let ring: [(usize, u8, bool); 4] = if up {
                    [(0, 2, true), (1, 1, true), (3, 3, false), (2, 0, false)]
                } else {
                    [(4, 0, true), (6, 3, true), (7, 1, false), (5, 2, false)]
                };
                let mut poly = Vec::with_capacity(8);
                for (c, side, fwd) in ring {
                    let p = ctx.corner(cell, c);
                    let (pi, pj) = (i + (c & 1), j + ((c >> 1) & 1));
                    let (bd, id) = (self.pillar_border(pi, pj), self.pillar_id(pi, pj));
                    poly.push(self.verts.get(p, region, bd, id));
                    if let Some(xs) = self.cross.get(&(cell, side, tb)) {
                        if fwd {
                            poly.extend_from_slice(xs);
                        } else {
                            poly.extend(xs.iter().rev());
                        }
                    }
                }
                if ctx.flip {
                    poly.reverse();
                }
                self.push(&poly, (4 + tb, fk), k, (j, i), cell, true, tol);
            }
        }
    }
}
