//! How a kernel uses each array it views, declared by type.
//!
//! A view is a [`DevSlice<T, A>`](crate::DevSlice) whose access `A` says what the kernel
//! may do with it: [`Write`] (read, write, atomics), [`Read`] (read only) or [`Unused`]
//! (nothing: the array is part of a group the kernel views whole but leaves alone). The
//! methods exist only where the access allows them, so a kernel that writes through a view
//! it declared read only does not compile (the explosions read the bodies' kinds):
//! ```compile_fail,E0599
//! use gpuwars_kernels::game::effects::EffectsArgs;
//! fn burst(args: &EffectsArgs) {
//!     args.bodies.kind.set(0, 1);
//! }
//! ```
//! nor does one that reads what it declared unused (the explosions leave the bodies'
//! states alone):
//! ```compile_fail,E0599
//! use gpuwars_kernels::game::effects::EffectsArgs;
//! fn burst(args: &EffectsArgs) -> u32 {
//!     args.bodies.state.get(0)
//! }
//! ```
//! while reading what it declared read is taken:
//! ```
//! use gpuwars_kernels::game::effects::EffectsArgs;
//! fn burst(args: &EffectsArgs) -> u32 {
//!     args.bodies.kind.get(0)
//! }
//! ```
//! A group of arrays ([`device_data!`](crate::device_data)) takes its arrays' access from a
//! second parameter: one of the three markers for the whole group, or a struct declared with
//! [`access!`](crate::access!) that names each array's. The host reads the declarations off
//! the argument struct's types when it binds a launch (each view it makes is of the access
//! its field's type asks for), so what an op declares is what its kernel can do.

/// What a kernel may do with an array, as a value: read off an [`Access`] type.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Use {
    /// Nothing: the view carries no memory.
    Unused,
    /// Read it.
    Read,
    /// Write it (and read it, and change it atomically).
    Write,
}

/// One of the three access markers; sealed, so that the kernels' views are only ever of
/// these.
pub trait Access: Copy + Send + Sync + 'static + sealed::Sealed {
    /// The use this marker allows.
    const USE: Use;
}

/// The markers whose views can be read ([`Read`] and [`Write`]).
pub trait Readable: Access {}

/// Read only: `get` and the reads built on it.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Read;

/// Read and written: `set` and the atomics too.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Write;

/// Not used at all: no method, and no memory behind the view.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Unused;

impl Access for Read {
    const USE: Use = Use::Read;
}
impl Access for Write {
    const USE: Use = Use::Write;
}
impl Access for Unused {
    const USE: Use = Use::Unused;
}
impl Readable for Read {}
impl Readable for Write {}

/// `Self` allows no more than `A` does: a view of access `A` may be narrowed to one of
/// `Self` (`DevSlice::restrict`), as a kernel that runs another's code in its own launch
/// hands that code the views at the other's access.
pub trait Within<A: Access>: Access {}
impl<A: Readable> Within<A> for Read {}
impl Within<Write> for Write {}
impl<A: Access> Within<A> for Unused {}

mod sealed {
    pub trait Sealed {}
    impl Sealed for super::Read {}
    impl Sealed for super::Write {}
    impl Sealed for super::Unused {}
}

/// Declares how a kernel uses each array of a group: a marker struct implementing the
/// group's access trait (named in its [`device_data!`](crate::device_data)), every array
/// and nested group named with its access. A name left out or misspelt does not compile.
///
/// ```ignore
/// access! {
///     /// What `think` does with the bodies.
///     pub struct Thinking: BodiesAccess {
///         pos: Read, vel: Read, force: Write, /* …every array… */
///         rng: Write,
///     }
/// }
/// ```
#[macro_export]
macro_rules! access {
    (
        $(#[$meta:meta])*
        pub struct $name:ident: $group:path {
            $( $field:ident: $access:ty, )*
        }
    ) => {
        $(#[$meta])*
        #[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
        pub struct $name;
        impl $group for $name {
            $( type $field = $access; )*
        }
    };
}
