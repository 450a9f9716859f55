//! Typed indices. Each kind of index (a definition, an atlas, a material, an IR node)
//! is its own type, so one cannot be used where another is meant.

/// Defines a typed index: a `u32` newtype with [`new`](#method.new) and `index()`.
macro_rules! define_id {
    ($(#[$attr:meta])* $name:ident) => {
        $(#[$attr])*
        #[derive(Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord, Debug)]
        pub struct $name(u32);

        impl $name {
            /// The ID of the element at `index`.
            pub fn new(index: usize) -> Self {
                $name(u32::try_from(index).expect(concat!(stringify!($name), " overflows u32")))
            }

            /// The position of the element in its list.
            pub fn index(self) -> usize {
                self.0 as usize
            }
        }
    };
}

pub(crate) use define_id;

#[cfg(test)]
mod tests {
    define_id!(
        /// An ID for the test.
        TestId
    );

    #[test]
    fn an_id_round_trips_its_index_and_orders_by_it() {
        let a = TestId::new(3);
        assert_eq!(a.index(), 3);
        assert!(TestId::new(2) < a);
        assert_eq!(a, TestId::new(3));
    }
}
