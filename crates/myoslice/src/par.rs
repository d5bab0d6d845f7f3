//! Data-parallel loops. With the `parallel` feature (the default) they run on rayon's
//! thread pool; without it (a web page, which has no threads) the same calls are plain
//! iterators on the calling thread. Every loop in the core is written so that its result
//! does not depend on how the work is split (no floating-point reduction across items in
//! an order the pool chooses), so both give the same bits.

#[cfg(feature = "parallel")]
pub use rayon::join;
#[cfg(feature = "parallel")]
pub use rayon::prelude::*;

#[cfg(not(feature = "parallel"))]
pub use serial::*;

/// rayon's names over std's iterators, in order on the calling thread.
#[cfg(not(feature = "parallel"))]
mod serial {
    /// Runs `a`, then `b`.
    pub fn join<A, B, RA, RB>(a: A, b: B) -> (RA, RB)
    where
        A: FnOnce() -> RA,
        B: FnOnce() -> RB,
    {
        let ra = a();
        (ra, b())
    }

    /// `into_par_iter`: `into_iter`.
    pub trait IntoParallelIterator: IntoIterator + Sized {
        /// The iterator, in order.
        fn into_par_iter(self) -> Self::IntoIter {
            self.into_iter()
        }
    }
    impl<I: IntoIterator> IntoParallelIterator for I {}

    /// `par_iter`: `iter`.
    pub trait IntoParallelRefIterator<'a> {
        /// The iterator over references.
        type Iter: Iterator;
        /// The iterator, in order.
        fn par_iter(&'a self) -> Self::Iter;
    }
    impl<'a, T: 'a + ?Sized> IntoParallelRefIterator<'a> for T
    where
        &'a T: IntoIterator,
    {
        type Iter = <&'a T as IntoIterator>::IntoIter;
        fn par_iter(&'a self) -> Self::Iter {
            self.into_iter()
        }
    }

    /// `par_iter_mut`: `iter_mut`.
    pub trait IntoParallelRefMutIterator<'a> {
        /// The iterator over mutable references.
        type Iter: Iterator;
        /// The iterator, in order.
        fn par_iter_mut(&'a mut self) -> Self::Iter;
    }
    impl<'a, T: 'a + ?Sized> IntoParallelRefMutIterator<'a> for T
    where
        &'a mut T: IntoIterator,
    {
        type Iter = <&'a mut T as IntoIterator>::IntoIter;
        fn par_iter_mut(&'a mut self) -> Self::Iter {
            self.into_iter()
        }
    }

    /// `par_chunks`: `chunks`.
    pub trait ParallelSlice<T> {
        /// Chunks of `size`, in order.
        fn par_chunks(&self, size: usize) -> std::slice::Chunks<'_, T>;
    }
    impl<T> ParallelSlice<T> for [T] {
        fn par_chunks(&self, size: usize) -> std::slice::Chunks<'_, T> {
            self.chunks(size)
        }
    }

    /// `par_chunks_mut`: `chunks_mut`.
    pub trait ParallelSliceMut<T> {
        /// Mutable chunks of `size`, in order.
        fn par_chunks_mut(&mut self, size: usize) -> std::slice::ChunksMut<'_, T>;
    }
    impl<T> ParallelSliceMut<T> for [T] {
        fn par_chunks_mut(&mut self, size: usize) -> std::slice::ChunksMut<'_, T> {
            self.chunks_mut(size)
        }
    }

    /// `par_extend`: `extend`.
    pub trait ParallelExtend<T> {
        /// Appends the items, in order.
        fn par_extend<I: IntoIterator<Item = T>>(&mut self, items: I);
    }
    impl<T> ParallelExtend<T> for Vec<T> {
        fn par_extend<I: IntoIterator<Item = T>>(&mut self, items: I) {
            self.extend(items);
        }
    }

    /// rayon's iterator adaptors that std names otherwise.
    pub trait ParallelIterator: Iterator + Sized {
        /// `flat_map_iter`: `flat_map`.
        fn flat_map_iter<U, F>(self, f: F) -> std::iter::FlatMap<Self, U, F>
        where
            U: IntoIterator,
            F: FnMut(Self::Item) -> U,
        {
            self.flat_map(f)
        }
    }
    impl<I: Iterator> ParallelIterator for I {}
}
