//! The object kinds: one registry line per kind ([`KINDS`]) with what the layers above decide
//! by kind, so that none of them names one. An object's kind is its label ([`super::Object::kind_name`]);
//! what a kind carries beyond its tiles (a height field's grid, a reservoir grid's blocks) is
//! reached through [`super::Object::heightfield`] and [`super::Object::grid`], never by matching
//! the kind.
//!
//! Adding a kind: its `add_*` in its own file of this module (building tiles), a line here, and
//! its tests. Every strategy and the draw then work on it unchanged, since they see tiles.

/// What is decided by an object's kind.
#[derive(Debug, PartialEq, Eq)]
pub struct Kind {
    /// The label objects of this kind carry.
    pub name: &'static str,
    /// The depth-tie priority of its objects unless given their own (0..=[`super::MAX_PRIORITY`];
    /// of two coincident surfaces the higher is seen, [`super::Object::priority`]).
    pub priority: u8,
    /// Translucent objects of this kind are drawn by the one of their stacks of tiles (tile
    /// column `ix` 0, 1, 2: the stacks along x, y, z) most nearly facing the view, as a volume
    /// lens is; other translucent objects draw all their tiles.
    pub one_stack: bool,
}

const fn kind(name: &'static str, priority: u8, one_stack: bool) -> Kind {
    Kind { name, priority, one_stack }
}

/// Every kind, one line each. A mesh given another label by its user ([`super::Scene::add_mesh`]'s
/// `kind`) behaves as "mesh".
pub const KINDS: &[Kind] = &[
    kind("well", 5, false), // tubes around deviated paths (well.rs): seen on the horizon they cross
    kind("heightfield", 4, false), // horizons (heightfield.rs): drawn exactly where they are
    kind("fault", 3, false), // triangle meshes (mesh.rs)
    kind("isosurface", 3, false), // crate::iso::scene_object
    kind("mesh", 3, false), // any other mesh (mesh.rs)
    kind("grid", 2, false), // reservoir grids (grid.rs): a grid's top below the horizon it follows
    kind("slice", 1, false), // seismic slices (slice.rs)
    kind("lens", 0, true),  // volume lenses (lens.rs): never hide what they enclose
];

/// The kind of label `name` ("mesh"'s for a label no line holds).
pub fn of(name: &str) -> &'static Kind {
    let find = |n: &str| KINDS.iter().find(|k| k.name == n);
    find(name).or_else(|| find("mesh")).expect("the registry has a line for meshes")
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn names_are_unique_and_priorities_in_range() {
        for (i, k) in KINDS.iter().enumerate() {
            assert!(KINDS[..i].iter().all(|o| o.name != k.name), "{} twice", k.name);
            assert!(k.priority <= super::super::MAX_PRIORITY);
        }
    }

    #[test]
    fn a_users_label_is_a_mesh() {
        assert_eq!(of("salt body"), of("mesh"));
        assert_eq!(of("lens").priority, 0);
        assert!(of("lens").one_stack && !of("slice").one_stack);
    }
}
