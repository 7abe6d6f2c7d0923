# use core::marker::PhantomData;
# use gpuwars_kernels::data::{Build, Convert, Store, View};
# use gpuwars_kernels::device_data;
# impl<S: Store> Hand<S> {
#     pub fn build<B: Build<S>>(_: &mut B) -> Result<Self, B::Error> {
#         Ok(Hand { flag: 0, count: 0, store: PhantomData })
#     }
#     pub fn convert<T: Store, C: Convert<S, T>>(&self, _: &mut C) -> Result<Hand<T>, C::Error> {
#         Ok(Hand { flag: self.flag, count: self.count, store: PhantomData })
#     }
# }
#[repr(C)]
#[derive(Clone, Copy, Debug)]
