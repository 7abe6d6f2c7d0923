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
use crate::access::Access;

/// Plain-data element types that device arrays can hold: any `bytemuck::Pod` type that is
/// sendable between threads (numbers, `glam::Vec2`, the kernels' `#[repr(C)]` structs).
pub trait Element: bytemuck::Pod + Send + Sync {}
impl<T: bytemuck::Pod + Send + Sync> Element for T {}

/// How a group's arrays are held: one type for the arrays of each element type and access
/// (the access matters to the kernels' view only).
pub trait Store {
    /// An array of `T` in this store, which a kernel uses as `A` says.
    type Array<T: Element, A: Access>;
}

/// The kernels' view: each array a [`DevSlice`] of its declared access.
#[derive(Clone, Copy, Debug)]
pub struct View;

impl Store for View {
    type Array<T: Element, A: Access> = DevSlice<T, A>;
}

/// Sizes only: what a group takes is counted (see [`Sizes`]) before anything is made.
#[derive(Clone, Copy, Debug)]
pub struct Unmade;

impl Store for Unmade {
    type Array<T: Element, A: Access> = ();
}

/// Makes each array of a group in store `S` from its name (`Group.field`) and element count.
pub trait Build<S: Store> {
    /// What can go wrong.
    type Error;
    /// The array `name` of `len` elements.
    fn array<T: Element, A: Access>(
        &mut self,
        name: &'static str,
        len: usize,
    ) -> Result<S::Array<T, A>, Self::Error>;
}

/// Turns each array of a group held in store `From` into the same array held in store `To`,
/// perhaps of another access (`In`, `Out`).
pub trait Convert<From: Store, To: Store> {
    /// What can go wrong.
    type Error;
    /// Array `name` of store `From` as store `To` holds it.
    fn array<T: Element, In: Access, Out: Access>(
        &mut self,
        name: &'static str,
        array: &From::Array<T, In>,
    ) -> Result<To::Array<T, Out>, Self::Error>;
}

/// Narrows a group's views to the access `To` declares (see [`crate::access::Within`]): a
/// kernel that runs another's code in its launch hands it its arguments so.
pub trait Restrict<To> {
    /// The same views, of `To`'s access.
    fn restrict(&self) -> To;
}

/// Counts the bytes a group's arrays take: `Group::<Unmade>::build(&mut sizes, ..)`.
#[derive(Clone, Copy, Debug, Default)]
pub struct Sizes {
    /// Bytes of the arrays built so far.
    pub bytes: u64,
}

impl Build<Unmade> for Sizes {
    type Error = core::convert::Infallible;
    fn array<T: Element, A: Access>(
        &mut self,
        _: &'static str,
        len: usize,
    ) -> Result<(), Self::Error> {
        self.bytes += (len * size_of::<T>()) as u64;
        Ok(())
    }
}

/// Declares a group of device arrays once (see the [module](self)), and the trait of its
/// access declarations (see [`mod@crate::access`]).
///
/// ```ignore
/// device_data! {
///     /// What the group is.
///     pub struct Contacts(slots): ContactsAccess {
///         /// Displacement.
///         push: [Vec2; slots],
///     } nested {
///         /// A group of arrays inside this one, built with the arguments given, and the
///         /// trait of its access declarations.
///         rng: RngStreams(slots): RngStreamsAccess,
///     }
/// }
/// ```
/// Each length is an expression of the group's parameters (element counts). The group is
/// generic over its store `S` and its access `M`: the kernels' `Contacts<View, M>` views
/// array `push` as a `DevSlice<Vec2, M::push>`; `M` is [`Write`](crate::access::Write)
/// (the default), [`Read`](crate::access::Read) or [`Unused`](crate::access::Unused) for
/// the whole group, or a struct of [`access!`](crate::access!) for each array.
///
/// A nested group must be plain data itself (`bytemuck::NoUninit`): a group of this macro,
/// or one that proves it. A hand-written group with a hole inside is refused, since the
/// hole's bytes would go to the device with the outer group's:
/// ```compile_fail,E0277
#[doc = include_str!("../doc/hand_written_group.rs")]
/// struct Hand<S: Store = View, M: HandAccess = Write> {
///     flag: u8, // three bytes of padding follow
///     count: u32,
///     store: PhantomData<(S, M)>,
/// }
/// device_data! { pub struct Outer(n): OuterAccess { xs: [u32; n], } nested { hand: Hand(): HandAccess, } }
/// ```
/// The same group without the hole is taken:
/// ```
#[doc = include_str!("../doc/hand_written_group.rs")]
/// struct Hand<S: Store = View, M: HandAccess = Write> {
///     flag: u32,
///     count: u32,
///     store: PhantomData<(S, M)>,
/// }
/// // SAFETY: two `u32`s and a zero-sized marker, `repr(C)`: no padding.
/// unsafe impl<M: HandAccess> gpuwars_kernels::__private::bytemuck::NoUninit for Hand<View, M> {}
/// device_data! { pub struct Outer(n): OuterAccess { xs: [u32; n], } nested { hand: Hand(): HandAccess, } }
/// ```
#[macro_export]
macro_rules! device_data {
    (
        $(#[$meta:meta])*
        pub struct $name:ident($($param:ident),*): $access:ident {
            $( $(#[$fmeta:meta])* $field:ident : [$elem:ty; $len:expr], )*
        }
        $( nested {
            $( $(#[$gmeta:meta])* $group:ident : $gty:ident($($garg:expr),*): $gaccess:ident, )*
        } )?
    ) => {
        $(#[$meta])*
        #[repr(C)]
        pub struct $name<
            S: $crate::data::Store = $crate::data::View,
            M: $access = $crate::access::Write,
        > {
            $( $(#[$fmeta])* pub $field: S::Array<$elem, M::$field>, )*
            $($( $(#[$gmeta])* pub $group: $gty<S, M::$group>, )*)?
        }

        #[doc = concat!("How a kernel uses each array of [`", stringify!($name), "`]: one \
            access a name (see the kernels' `access` module).")]
        #[allow(non_camel_case_types)]
        pub trait $access: Copy + Send + Sync + 'static {
            $(
                #[doc = concat!("The access to `", stringify!($field), "`.")]
                type $field: $crate::access::Access;
            )*
            $($(
                #[doc = concat!("The access to the arrays of `", stringify!($group), "`.")]
                type $group: $gaccess;
            )*)?
        }
        $crate::device_data!(@uniform $access, $crate::access::Read, $($field)*; $($($group)*)?);
        $crate::device_data!(@uniform $access, $crate::access::Write, $($field)*; $($($group)*)?);
        $crate::device_data!(@uniform $access, $crate::access::Unused, $($field)*; $($($group)*)?);

        impl<S: $crate::data::Store, M: $access> $name<S, M> {
            /// Makes every array with `build`, each of the length the declaration gives.
            pub fn build<B: $crate::data::Build<S>>(
                build: &mut B,
                $($param: usize),*
            ) -> Result<Self, B::Error> {
                Ok($name {
                    $( $field: build.array::<$elem, M::$field>(
                        concat!(stringify!($name), ".", stringify!($field)),
                        $len,
                    )?, )*
                    $($( $group: <$gty<S, M::$group>>::build(build, $($garg),*)?, )*)?
                })
            }

            /// The same arrays, each turned by `convert` into store `B`'s, of the access `N`
            /// declares.
            pub fn convert<B: $crate::data::Store, N: $access, C: $crate::data::Convert<S, B>>(
                &self,
                convert: &mut C,
            ) -> Result<$name<B, N>, C::Error> {
                Ok($name {
                    $( $field: convert.array::<$elem, M::$field, N::$field>(
                        concat!(stringify!($name), ".", stringify!($field)),
                        &self.$field,
                    )?, )*
                    $($( $group: self.$group.convert::<B, N::$group, C>(convert)?, )*)?
                })
            }
        }

        impl<M: $access, N: $access> $crate::data::Restrict<$name<$crate::data::View, N>>
            for $name<$crate::data::View, M>
        where
            $( N::$field: $crate::access::Within<M::$field>, )*
            $($( $gty<$crate::data::View, M::$group>:
                $crate::data::Restrict<$gty<$crate::data::View, N::$group>>, )*)?
        {
            #[inline(always)]
            fn restrict(&self) -> $name<$crate::data::View, N> {
                $name {
                    $( $field: self.$field.restrict(), )*
                    $($( $group: self.$group.restrict(), )*)?
                }
            }
        }

        impl<S: $crate::data::Store, M: $access> Clone for $name<S, M>
        where
            $( S::Array<$elem, M::$field>: Clone, )*
            $($( $gty<S, M::$group>: Clone, )*)?
        {
            fn clone(&self) -> Self {
                $name {
                    $( $field: self.$field.clone(), )*
                    $($( $group: self.$group.clone(), )*)?
                }
            }
        }
        impl<M: $access> Copy for $name<$crate::data::View, M> {}

        impl<S: $crate::data::Store, M: $access> PartialEq for $name<S, M>
        where
            $( S::Array<$elem, M::$field>: PartialEq, )*
            $($( $gty<S, M::$group>: PartialEq, )*)?
        {
            fn eq(&self, other: &Self) -> bool {
                true $( && self.$field == other.$field )* $($( && self.$group == other.$group )*)?
            }
        }

        impl<S: $crate::data::Store, M: $access> core::fmt::Debug for $name<S, M>
        where
            $( S::Array<$elem, M::$field>: core::fmt::Debug, )*
            $($( $gty<S, M::$group>: core::fmt::Debug, )*)?
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
        // Every nested group is plain data itself, whatever its access: one `device_data!`
        // made, or one whose own `NoUninit` proves it (a group with a hole inside has none,
        // and is refused).
        $($(
            const _: fn() = || {
                fn plain<T: $crate::__private::bytemuck::NoUninit>() {}
                fn each<M: $gaccess>() {
                    plain::<$gty<$crate::data::View, M>>();
                }
                each::<$crate::access::Write>();
            };
        )*)?
        // SAFETY: `repr(C)` fields that are all `NoUninit` (views of any access, and nested
        // groups, checked above), with no padding between them (asserted above; the access
        // changes no view's layout).
        unsafe impl<M: $access> $crate::__private::bytemuck::NoUninit
            for $name<$crate::data::View, M> {}
    };
    (@uniform $access:ident, $marker:ty, $($field:ident)*; $($group:ident)*) => {
        impl $access for $marker {
            $( type $field = $marker; )*
            $( type $group = $marker; )*
        }
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
