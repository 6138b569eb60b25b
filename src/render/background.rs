//! The image's background, put in while the image is read back: one colour per image row (a
//! vertical gradient, or one colour), at the pixels where nothing was drawn.
//!
//! The passes clear to opaque black, and translucent lenses and slices drawn over nothing blend
//! with that black. A pixel takes its row's background colour when its depth is +inf (no opaque
//! fragment: `RenderOutput::depth`) and its colour is still that black (nothing translucent drawn
//! over it either); every other pixel, and alpha everywhere, is left as drawn.

use crate::error::{ensure, Result};
use rayon::prelude::*;

/// Per image row (row 0 = top) its background colour, RGB8; checked against the image's height.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Background(Vec<[u8; 3]>);

impl Background {
    /// The rows of `rgb` (3 bytes per row, row 0 first) for images `height` rows tall. Input error
    /// naming `background` when `rgb` does not hold exactly `height` rows.
    pub fn from_rows(rgb: &[u8], height: u32) -> Result<Self> {
        ensure(rgb.len() == 3 * height as usize, "background", || {
            format!("{} bytes of row colours; expected 3 per image row, {}", rgb.len(), 3 * height as u64)
        })?;
        Ok(Self(rgb.chunks_exact(3).map(|c| [c[0], c[1], c[2]]).collect()))
    }

    /// Fills `image` (RGBA8, row-major, `depth.len()` pixels, as many rows as this background)
    /// where nothing was drawn (module docs). Rows go in parallel.
    pub fn fill(&self, image: &mut [u8], depth: &[f32]) {
        let rows = self.0.len();
        if rows == 0 || depth.is_empty() {
            return;
        }
        let w = depth.len() / rows;
        debug_assert_eq!((w * rows, image.len()), (depth.len(), 4 * depth.len()));
        image.par_chunks_mut(4 * w).zip(depth.par_chunks(w)).zip(&self.0).for_each(|((px, d), bg)| {
            for (p, &z) in px.chunks_exact_mut(4).zip(d) {
                if z == f32::INFINITY && p[..3] == [0, 0, 0] {
                    p[..3].copy_from_slice(bg);
                }
            }
        });
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn only_empty_black_pixels_take_their_rows_colour() {
        let bg = Background::from_rows(&[10, 20, 30, 40, 50, 60], 2).unwrap();
        let inf = f32::INFINITY;
        // Row 0: empty black, drawn black (finite depth), translucent over nothing (not black).
        // Row 1: empty black, drawn.
        let depth = [inf, 5.0, inf, inf, 2.0, 3.0];
        let mut image = vec![0, 0, 0, 255, 0, 0, 0, 255, 7, 0, 0, 255, 0, 0, 0, 255, 1, 2, 3, 255, 0, 0, 0, 9];
        bg.fill(&mut image, &depth);
        let want = vec![10, 20, 30, 255, 0, 0, 0, 255, 7, 0, 0, 255, 40, 50, 60, 255, 1, 2, 3, 255, 0, 0, 0, 9];
        assert_eq!(image, want);
    }

    #[test]
    fn rows_must_match_the_image_height() {
        let e = Background::from_rows(&[1, 2, 3, 4, 5], 2).unwrap_err().to_string();
        assert!(e.contains("background") && e.contains("5 bytes"), "{e}");
        assert!(Background::from_rows(&[], 1).is_err());
        assert_eq!(Background::from_rows(&[], 0).unwrap(), Background(vec![]));
    }
}
