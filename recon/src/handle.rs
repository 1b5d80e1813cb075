//! The typed `u32` element handles that the surface mesh and the curve network share: one macro, so every
//! handle has the same constructor, index, serde form (a bare number) and printed form (`v12`, `f3`, ...).

/// Declares a handle type: `handle!(/// doc, Name, "prefix")`.
macro_rules! handle {
    ($(#[$doc:meta])* $name:ident, $prefix:literal) => {
        $(#[$doc])*
        #[derive(
            Clone, Copy, PartialEq, Eq, PartialOrd, Ord, Hash, serde::Serialize, serde::Deserialize,
        )]
        #[serde(transparent)]
        pub struct $name(pub(crate) u32);

        impl $name {
            /// Builds a handle from an index. No check is made that the element exists.
            pub const fn new(index: usize) -> Self {
                Self(index as u32)
            }
            /// The index of this element's slot in its container's arrays.
            pub const fn idx(self) -> usize {
                self.0 as usize
            }
        }

        impl std::fmt::Debug for $name {
            fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
                write!(f, concat!($prefix, "{}"), self.0)
            }
        }

        impl std::fmt::Display for $name {
            fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
                std::fmt::Debug::fmt(self, f)
            }
        }
    };
}

pub(crate) use handle;
