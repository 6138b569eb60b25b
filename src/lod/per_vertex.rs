//! [`PerVertex`]: a tile's optional per-vertex attribute (values, smooth normals, grid
//! coordinates), one pointer wide in its tile.
//!
//! Most tiles have none of these attributes (a height field has no normals nor grid coordinates,
//! most objects no values), and an empty tile read from bytes must stay within twice its record's
//! size in memory (issue 39, `tests/alloc_bound.rs`): an empty attribute is a null pointer (8
//! bytes, no allocation) rather than an empty `Vec` (24 bytes), and a non-empty one a boxed `Vec`
//! (24 bytes more on the heap beside its elements).

use std::ops::{Deref, DerefMut};

/// An optional per-vertex attribute of a tile: empty (no allocation), or a `Vec` behind one
/// pointer. Reads as a slice (`Deref<Target = [T]>`); grows like a `Vec` (`push`, `extend`).
#[derive(Clone, PartialEq)]
// The box is the point: one pointer in the tile, where a `Vec` takes three (a `Box<[T]>` two, and
// it could not grow as the builders push).
#[allow(clippy::box_collection)]
pub struct PerVertex<T>(Option<Box<Vec<T>>>);

impl<T> PerVertex<T> {
    /// An empty attribute (no allocation).
    pub const fn new() -> Self {
        Self(None)
    }

    /// The vector, allocated on first use.
    fn vec_mut(&mut self) -> &mut Vec<T> {
        self.0.get_or_insert_with(Box::default)
    }

    pub fn push(&mut self, v: T) {
        self.vec_mut().push(v);
    }

    /// Empties the attribute and frees what it held.
    pub fn clear(&mut self) {
        self.0 = None;
    }

    /// The elements as a `Vec` (empty: not allocated).
    pub fn into_vec(self) -> Vec<T> {
        self.0.map_or_else(Vec::new, |b| *b)
    }
}

impl<T> Default for PerVertex<T> {
    fn default() -> Self {
        Self::new()
    }
}

impl<T> Deref for PerVertex<T> {
    type Target = [T];
    fn deref(&self) -> &[T] {
        self.0.as_deref().map_or(&[], Vec::as_slice)
    }
}

impl<T> DerefMut for PerVertex<T> {
    fn deref_mut(&mut self) -> &mut [T] {
        match &mut self.0 {
            Some(v) => v.as_mut_slice(),
            None => &mut [],
        }
    }
}

/// An empty vector stays unallocated.
impl<T> From<Vec<T>> for PerVertex<T> {
    fn from(v: Vec<T>) -> Self {
        Self((!v.is_empty()).then(|| Box::new(v)))
    }
}

impl<T> FromIterator<T> for PerVertex<T> {
    fn from_iter<I: IntoIterator<Item = T>>(iter: I) -> Self {
        Vec::from_iter(iter).into()
    }
}

impl<T> Extend<T> for PerVertex<T> {
    fn extend<I: IntoIterator<Item = T>>(&mut self, iter: I) {
        let mut iter = iter.into_iter().peekable();
        if iter.peek().is_some() {
            self.vec_mut().extend(iter);
        }
    }
}

impl<'a, T> IntoIterator for &'a PerVertex<T> {
    type Item = &'a T;
    type IntoIter = std::slice::Iter<'a, T>;
    fn into_iter(self) -> Self::IntoIter {
        self.iter()
    }
}

impl<T: std::fmt::Debug> std::fmt::Debug for PerVertex<T> {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_list().entries(self.iter()).finish()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn empty_is_one_pointer_and_unallocated_and_reads_as_a_slice() {
        assert_eq!(std::mem::size_of::<PerVertex<f32>>(), 8);
        let mut a: PerVertex<u32> = Vec::new().into();
        assert!(a.0.is_none() && a.is_empty());
        a.extend(std::iter::empty());
        assert!(a.0.is_none());
        a.push(3);
        a.extend([4, 5]);
        a[0] += 1;
        assert_eq!(&*a, &[4, 4, 5]);
        assert_eq!(a.iter().sum::<u32>(), 13);
        assert_eq!(format!("{a:?}"), "[4, 4, 5]");
        assert_eq!(a.clone().into_vec(), vec![4, 4, 5]);
        a.clear();
        assert!(a.0.is_none() && a == PerVertex::default());
    }
}
