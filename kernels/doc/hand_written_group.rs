# use core::marker::PhantomData;
# use gpuwars_kernels::access::{Read, Unused, Write};
# use gpuwars_kernels::data::{Build, Convert, Store, View};
# use gpuwars_kernels::device_data;
# trait HandAccess: Copy + Send + Sync + 'static {}
# impl HandAccess for Read {}
# impl HandAccess for Write {}
# impl HandAccess for Unused {}
# impl<S: Store, M: HandAccess> Hand<S, M> {
#     pub fn build<B: Build<S>>(_: &mut B) -> Result<Self, B::Error> {
#         Ok(Hand { flag: 0, count: 0, store: PhantomData })
#     }
#     pub fn convert<T: Store, N: HandAccess, C: Convert<S, T>>(
#         &self,
#         _: &mut C,
#     ) -> Result<Hand<T, N>, C::Error> {
#         Ok(Hand { flag: self.flag, count: self.count, store: PhantomData })
#     }
# }
#[repr(C)]
#[derive(Clone, Copy, Debug)]
