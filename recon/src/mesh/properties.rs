//! Named, typed per-element property arrays (pmp-library style) that follow the mesh
//! through element insertion and garbage collection.

use std::any::Any;
use std::collections::BTreeMap;
use std::marker::PhantomData;

use super::error::MeshError;

/// Type-erased storage of one property array.
trait PropertyArray: Any {
    fn push_default(&mut self);
    /// Keeps element `keep[i]` at slot `i`; the array shrinks to `keep.len()`.
    fn compact(&mut self, keep: &[usize]);
    fn as_any(&self) -> &dyn Any;
    fn as_any_mut(&mut self) -> &mut dyn Any;
}

impl<T: Clone + Default + 'static> PropertyArray for Vec<T> {
    fn push_default(&mut self) {
        self.push(T::default());
    }
    fn compact(&mut self, keep: &[usize]) {
        let kept: Vec<T> = keep.iter().map(|&i| self[i].clone()).collect();
        *self = kept;
    }
    fn as_any(&self) -> &dyn Any {
        self
    }
    fn as_any_mut(&mut self) -> &mut dyn Any {
        self
    }
}

/// A typed key for a property array of values `T` attached to elements of kind `H`.
#[derive(Debug)]
pub struct Property<H, T> {
    name: String,
    _marker: PhantomData<fn() -> (H, T)>,
}

impl<H, T> Clone for Property<H, T> {
    fn clone(&self) -> Self {
        Self {
            name: self.name.clone(),
            _marker: PhantomData,
        }
    }
}

impl<H, T> Property<H, T> {
    /// The property's name.
    pub fn name(&self) -> &str {
        &self.name
    }
}

/// All property arrays for one element kind; every array has `len` entries.
#[derive(Default)]
pub struct PropertyContainer {
    arrays: BTreeMap<String, Box<dyn PropertyArray>>,
    len: usize,
}

impl std::fmt::Debug for PropertyContainer {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("PropertyContainer")
            .field("names", &self.arrays.keys().collect::<Vec<_>>())
            .field("len", &self.len)
            .finish()
    }
}

impl Clone for PropertyContainer {
    /// Properties are not cloned with the mesh (their types are erased); the clone has none.
    fn clone(&self) -> Self {
        Self {
            arrays: BTreeMap::new(),
            len: self.len,
        }
    }
}

impl PropertyContainer {
    /// Adds a property filled with `init`; fails if the name is taken.
    pub fn add<H, T: Clone + Default + 'static>(
        &mut self,
        name: &str,
        init: T,
    ) -> Result<Property<H, T>, MeshError> {
        if self.arrays.contains_key(name) {
            return Err(MeshError::PropertyExists(name.to_owned()));
        }
        self.arrays
            .insert(name.to_owned(), Box::new(vec![init; self.len]));
        Ok(Property {
            name: name.to_owned(),
            _marker: PhantomData,
        })
    }

    /// Looks up an existing property by name and type.
    pub fn get<H, T: 'static>(&self, name: &str) -> Option<Property<H, T>> {
        let array = self.arrays.get(name)?;
        array.as_any().downcast_ref::<Vec<T>>()?;
        Some(Property {
            name: name.to_owned(),
            _marker: PhantomData,
        })
    }

    /// Removes a property.
    pub fn remove<H, T>(&mut self, p: Property<H, T>) {
        self.arrays.remove(&p.name);
    }

    /// The values of a property, indexed by element index.
    pub fn values<H, T: 'static>(&self, p: &Property<H, T>) -> Option<&[T]> {
        let v = self
            .arrays
            .get(&p.name)?
            .as_any()
            .downcast_ref::<Vec<T>>()?;
        Some(v.as_slice())
    }

    /// Mutable values of a property, indexed by element index.
    pub fn values_mut<H, T: 'static>(&mut self, p: &Property<H, T>) -> Option<&mut [T]> {
        let v = self
            .arrays
            .get_mut(&p.name)?
            .as_any_mut()
            .downcast_mut::<Vec<T>>()?;
        Some(v.as_mut_slice())
    }

    pub(crate) fn push(&mut self) {
        self.len += 1;
        for a in self.arrays.values_mut() {
            a.push_default();
        }
    }

    pub(crate) fn compact(&mut self, keep: &[usize]) {
        self.len = keep.len();
        for a in self.arrays.values_mut() {
            a.compact(keep);
        }
    }
}
