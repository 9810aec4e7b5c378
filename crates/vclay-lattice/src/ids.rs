//! Typed element ids.
//!
//! Every element of a [`crate::Lattice`] is addressed by a `u32` index wrapped in a newtype, so a
//! face id can never be passed where a cell id is expected. Ids are dense: the elements of a lattice
//! are numbered `0..count`. [`CellId::NONE`] marks the missing side of a boundary face.

use std::fmt;

macro_rules! id_type {
    ($(#[$doc:meta])* $name:ident, $label:literal) => {
        $(#[$doc])*
        #[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord, Hash, Default)]
        #[repr(transparent)]
        pub struct $name(pub u32);

        impl $name {
            /// The id as an index into the lattice's arrays.
            #[inline]
            pub fn index(self) -> usize {
                self.0 as usize
            }

            /// The id of the element at `index`.
            ///
            /// # Panics
            /// If `index` does not fit in `u32`.
            #[inline]
            #[track_caller]
            pub fn new(index: usize) -> Self {
                Self(u32::try_from(index).expect(concat!($label, " index overflows u32")))
            }
        }

        impl fmt::Display for $name {
            fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
                write!(f, concat!($label, " {}"), self.0)
            }
        }
    };
}

id_type!(
    /// Id of a lattice point (vertex).
    VertexId,
    "point"
);
id_type!(
    /// Id of a lattice edge.
    EdgeId,
    "edge"
);
id_type!(
    /// Id of a lattice face.
    FaceId,
    "face"
);
id_type!(
    /// Id of a lattice cell.
    CellId,
    "cell"
);

impl CellId {
    /// Sentinel for "no cell" (the outer side of a boundary face).
    pub const NONE: CellId = CellId(u32::MAX);

    /// Whether this is a real cell (not [`CellId::NONE`]).
    #[inline]
    pub fn is_some(self) -> bool {
        self != Self::NONE
    }

    /// `Some(self)` for a real cell, `None` for [`CellId::NONE`].
    #[inline]
    pub fn get(self) -> Option<CellId> {
        self.is_some().then_some(self)
    }
}
