//! Device data declared once.
//!
//! A group of device arrays (the bodies, the grid, the free lists, the game's buffers) is
//! written once, with [`device_data!`](crate::device_data), as a struct generic over a [`Store`]: how each array
//! is held. The same declaration is the kernels' view of it (`Group<View>`, the default: one
//! [`DevSlice`] an array, a padding-free kernel argument), the host's buffers
//! (`Group<Buffers>` on the host side), what a snapshot reads back (`Group<Vecs>`), and the
//! bytes the group takes before any is allocated ([`Sizes`]). The generated `build` makes
//! every array of a store from its name and length, `convert` turns one store into another
//! array by array: the host never lists a group's fields by hand.
//!
//! A kernel's argument struct is declared with [`kernel_args!`](crate::kernel_args), which
//! adds the layout (`#[repr(C)]`), the padding check (its size against its fields', each
//! `bytemuck::NoUninit`) and the crate's only `unsafe impl` of
//! [`KernelArgs`](crate::KernelArgs), with the reason it holds.

use crate::DevSlice;

/// Plain-data element types that device arrays can hold: any `bytemuck::Pod` type that is
/// sendable between threads (numbers, `glam::Vec2`, the kernels' `#[repr(C)]` structs).
pub trait Element: bytemuck::Pod + Send + Sync {}
impl<T: bytemuck::Pod + Send + Sync> Element for T {}

/// How a group's arrays are held: one type for the arrays of each element type.
pub trait Store {
    /// An array of `T` in this store.
    type Array<T: Element>;
}

/// The kernels' view: each array a [`DevSlice`].
#[derive(Clone, Copy, Debug)]
pub struct View;

impl Store for View {
    type Array<T: Element> = DevSlice<T>;
}

/// Sizes only: what a group takes is counted (see [`Sizes`]) before anything is made.
#[derive(Clone, Copy, Debug)]
pub struct Unmade;

impl Store for Unmade {
    type Array<T: Element> = ();
}

/// Makes each array of a group in store `S` from its name (`Group.field`) and element count.
pub trait Build<S: Store> {
    /// What can go wrong.
    type Error;
    /// The array `name` of `len` elements.
    fn array<T: Element>(
        &mut self,
        name: &'static str,
        len: usize,
    ) -> Result<S::Array<T>, Self::Error>;
}

/// Turns each array of a group held in store `A` into the same array held in store `B`.
pub trait Convert<A: Store, B: Store> {
    /// What can go wrong.
    type Error;
    /// Array `name` of store `A` as store `B` holds it.
    fn array<T: Element>(
        &mut self,
        name: &'static str,
        array: &A::Array<T>,
    ) -> Result<B::Array<T>, Self::Error>;
}

/// Counts the bytes a group's arrays take: `Group::<Unmade>::build(&mut sizes, ..)`.
#[derive(Clone, Copy, Debug, Default)]
pub struct Sizes {
    /// Bytes of the arrays built so far.
    pub bytes: u64,
}

impl Build<Unmade> for Sizes {
    type Error = core::convert::Infallible;
    fn array<T: Element>(&mut self, _: &'static str, len: usize) -> Result<(), Self::Error> {
        self.bytes += (len * size_of::<T>()) as u64;
        Ok(())
    }
}

/// Declares a group of device arrays once (see the [module](self)).
///
/// ```ignore
/// device_data! {
///     /// What the group is.
///     pub struct Contacts(slots) {
///         /// Displacement.
///         push: [Vec2; slots],
///     } nested {
///         /// A group of arrays inside this one, built with the arguments given.
///         rng: RngStreams(slots),
///     }
/// }
/// ```
/// Each length is an expression of the group's parameters (element counts).
///
/// A nested group must be plain data itself (`bytemuck::NoUninit`): a group of this macro,
/// or one that proves it. A hand-written group with a hole inside is refused, since the
/// hole's bytes would go to the device with the outer group's:
/// ```compile_fail,E0277
#[doc = include_str!("../doc/hand_written_group.rs")]
/// struct Hand<S: Store = View> {
///     flag: u8, // three bytes of padding follow
///     count: u32,
///     store: PhantomData<S>,
/// }
/// device_data! { pub struct Outer(n) { xs: [u32; n], } nested { hand: Hand(), } }
/// ```
/// The same group without the hole is taken:
/// ```
#[doc = include_str!("../doc/hand_written_group.rs")]
/// struct Hand<S: Store = View> {
///     flag: u32,
///     count: u32,
///     store: PhantomData<S>,
/// }
/// // SAFETY: two `u32`s and a zero-sized marker, `repr(C)`: no padding.
/// unsafe impl gpuwars_kernels::__private::bytemuck::NoUninit for Hand<View> {}
/// device_data! { pub struct Outer(n) { xs: [u32; n], } nested { hand: Hand(), } }
/// ```
#[macro_export]
macro_rules! device_data {
    (
        $(#[$meta:meta])*
        pub struct $name:ident($($param:ident),*) {
            $( $(#[$fmeta:meta])* $field:ident : [$elem:ty; $len:expr], )*
        }
        $( nested {
            $( $(#[$gmeta:meta])* $group:ident : $gty:ident($($garg:expr),*), )*
        } )?
    ) => {
        $(#[$meta])*
        #[repr(C)]
        pub struct $name<S: $crate::data::Store = $crate::data::View> {
            $( $(#[$fmeta])* pub $field: S::Array<$elem>, )*
            $($( $(#[$gmeta])* pub $group: $gty<S>, )*)?
        }

        impl<S: $crate::data::Store> $name<S> {
            /// Makes every array with `build`, each of the length the declaration gives.
            pub fn build<B: $crate::data::Build<S>>(
                build: &mut B,
                $($param: usize),*
            ) -> Result<Self, B::Error> {
                Ok($name {
                    $( $field: build.array::<$elem>(
                        concat!(stringify!($name), ".", stringify!($field)),
                        $len,
                    )?, )*
                    $($( $group: <$gty<S>>::build(build, $($garg),*)?, )*)?
                })
            }

            /// The same arrays, each turned by `convert` into store `B`'s.
            pub fn convert<B: $crate::data::Store, C: $crate::data::Convert<S, B>>(
                &self,
                convert: &mut C,
            ) -> Result<$name<B>, C::Error> {
                Ok($name {
                    $( $field: convert.array::<$elem>(
                        concat!(stringify!($name), ".", stringify!($field)),
                        &self.$field,
                    )?, )*
                    $($( $group: self.$group.convert(convert)?, )*)?
                })
            }
        }

        impl<S: $crate::data::Store> Clone for $name<S>
        where
            $( S::Array<$elem>: Clone, )*
            $($( $gty<S>: Clone, )*)?
        {
            fn clone(&self) -> Self {
                $name {
                    $( $field: self.$field.clone(), )*
                    $($( $group: self.$group.clone(), )*)?
                }
            }
        }
        impl Copy for $name<$crate::data::View> {}

        impl<S: $crate::data::Store> PartialEq for $name<S>
        where
            $( S::Array<$elem>: PartialEq, )*
            $($( $gty<S>: PartialEq, )*)?
        {
            fn eq(&self, other: &Self) -> bool {
                true $( && self.$field == other.$field )* $($( && self.$group == other.$group )*)?
            }
        }

        impl<S: $crate::data::Store> core::fmt::Debug for $name<S>
        where
            $( S::Array<$elem>: core::fmt::Debug, )*
            $($( $gty<S>: core::fmt::Debug, )*)?
        {
            fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
                f.debug_struct(stringify!($name))
                    $( .field(stringify!($field), &self.$field) )*
                    $($( .field(stringify!($group), &self.$group) )*)?
                    .finish()
            }
        }

        // No padding: the size is the sum of the fields' (16-byte views, groups of them).
        const _: () = assert!(
            size_of::<$name<$crate::data::View>>()
                == 0 $( + size_of::<$crate::DevSlice<$elem>>() )*
                    $($( + size_of::<$gty<$crate::data::View>>() )*)?
        );
        // Every nested group is plain data itself: one `device_data!` made, or one whose
        // own `NoUninit` proves it (a group with a hole inside has none, and is refused).
        $($(
            const _: fn() = || {
                fn plain<T: $crate::__private::bytemuck::NoUninit>() {}
                plain::<$gty<$crate::data::View>>();
            };
        )*)?
        // SAFETY: `repr(C)` fields that are all `NoUninit` (views, and nested groups,
        // checked above), with no padding between them (asserted above).
        unsafe impl $crate::__private::bytemuck::NoUninit for $name<$crate::data::View> {}
    };
}

/// Declares a kernel's argument struct: `#[repr(C)]`, plain data, no padding (its size
/// checked against its fields', each `bytemuck::NoUninit`), and
/// [`KernelArgs`](crate::KernelArgs).
#[macro_export]
macro_rules! kernel_args {
    (
        $(#[$meta:meta])*
        pub struct $name:ident {
            $( $(#[$fmeta:meta])* pub $field:ident : $ty:ty, )*
        }
    ) => {
        $(#[$meta])*
        #[repr(C)]
        #[derive(Clone, Copy, Debug)]
        pub struct $name {
            $( $(#[$fmeta])* pub $field: $ty, )*
        }
        // No padding: the size is the sum of the fields'.
        const _: () = assert!(size_of::<$name>() == 0 $( + size_of::<$ty>() )*);
        // Every field is plain data.
        const _: fn() = || {
            fn plain<T: $crate::__private::bytemuck::NoUninit>() {}
            $( plain::<$ty>(); )*
        };
        // SAFETY: `repr(C)` fields that are all `NoUninit` (checked above), with no padding
        // between or after them (asserted above).
        unsafe impl $crate::__private::bytemuck::NoUninit for $name {}
        // SAFETY: plain data without padding (above); its fields are numbers, plain
        // `repr(C)` structs and device views (`DevSlice`: an address and a length), never
        // references or host pointers, and any bit pattern of them is a value.
        unsafe impl $crate::KernelArgs for $name {}
    };
}
