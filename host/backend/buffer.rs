//! Buffers: device memory the host reaches through its [`Device`] (allocation, upload,
//! write, download, clear, copy), each knowing the device that made it.

use std::marker::PhantomData;
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::{Arc, Mutex};

use gpuwars_kernels::DevSlice;
use gpuwars_kernels::access::{Access, Use};
use gpuwars_kernels::data::{Build, Convert, Store};

use super::{Device, DeviceId, Element, Error, Imp, check_len, cpu, cuda};

/// A buffer of `T` in the device's memory (host memory under the emulator).
///
/// The host reads and writes it through the [`Device`] (`write`, `download`, `copy`), and
/// kernels through the views a [`Binder`](super::Binder) makes for an [`Op`](super::Op). The memory is shared with the
/// ops that view it ([`Buffer::hold`]): it is freed when the buffer and every op and plan
/// made with it are gone, not before.
///
/// Safe code cannot see the memory any other way: a buffer hands out no view of itself, so
/// this does not compile (a view would outlive the buffer it was made from, and read memory
/// the next upload reuses).
/// ```compile_fail,E0599
/// let dev = gpuwars::Device::cpu(Some(1), "probe").unwrap();
/// let view = dev.upload(&[7u32; 1024]).unwrap().view(); // the Buffer is dropped here
/// let _other = dev.upload(&[9u32; 1024]).unwrap();
/// println!("{}", view.get(0));
/// ```
pub struct Buffer<T: Element> {
    pub(super) imp: Arc<BufferImp<T>>,
    pub(super) device: DeviceId,
    /// Its array's name in its group, or its element type, for errors.
    name: &'static str,
    /// Whether a [`Ring`](super::Ring) owns the host's side of the memory: while one does,
    /// the host writes it through the ring only (see [`Buffer::check_writable`]).
    pub(super) ringed: Arc<AtomicBool>,
}

/// A share in a buffer's memory that keeps it allocated and gives no access to it: what an
/// [`Op`](super::Op) holds of each buffer its arguments view.
#[derive(Clone)]
pub struct Hold {
    _memory: Arc<dyn Send + Sync>,
}

pub(super) enum BufferImp<T: Element> {
    Cpu(cpu::HostBuffer<T>),
    /// Bytes on the GPU, `len` elements at `addr`; `T` is the type the bytes hold. cudarc's
    /// copies want the slice exclusively, which the lock gives while ops share the
    /// allocation.
    Cuda {
        bytes: Mutex<cudarc::driver::CudaSlice<u8>>,
        addr: u64,
        len: usize,
        _element: PhantomData<T>,
    },
    /// Page-locked host memory mapped into the GPU's address space, `len` elements: what the
    /// host and the steps in flight exchange without copies (see [`Ring`](super::ring::Ring)).
    Mapped {
        memory: cuda::Mapped,
        len: usize,
        _element: PhantomData<T>,
    },
}

impl<T: Element> BufferImp<T> {
    fn cuda(bytes: cudarc::driver::CudaSlice<u8>) -> Self {
        BufferImp::Cuda {
            addr: cuda::address(&bytes),
            len: bytes.len() / size_of::<T>(),
            bytes: Mutex::new(bytes),
            _element: PhantomData,
        }
    }
}

/// The GPU bytes of a buffer, locked for a copy.
fn locked(
    bytes: &Mutex<cudarc::driver::CudaSlice<u8>>,
) -> std::sync::MutexGuard<'_, cudarc::driver::CudaSlice<u8>> {
    bytes.lock().unwrap_or_else(|e| e.into_inner())
}

impl<T: Element> Buffer<T> {
    /// Number of elements.
    pub fn len(&self) -> usize {
        match &*self.imp {
            BufferImp::Cpu(b) => b.len(),
            BufferImp::Cuda { len, .. } | BufferImp::Mapped { len, .. } => *len,
        }
    }

    /// Whether the buffer holds no element.
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }

    /// The device whose memory holds it.
    pub fn device(&self) -> DeviceId {
        self.device
    }

    /// The same buffer, called `name` where errors speak of it (its element type until
    /// named; a group's arrays are named for their fields).
    pub fn named(self, name: &'static str) -> Buffer<T> {
        Buffer { name, ..self }
    }

    /// What errors call it.
    pub fn name(&self) -> &'static str {
        self.name
    }

    /// `Ok` unless a ring owns the buffer's host side, which only the ring then writes.
    fn check_writable(&self) -> Result<(), Error> {
        match self.ringed.load(Ordering::Acquire) {
            false => Ok(()),
            true => Err(Error::Invalid(format!(
                "buffer `{}` belongs to a ring: the host writes it only through the ring \
                 while the ring exists",
                self.name
            ))),
        }
    }

    /// Which allocation this is, for telling two buffers apart (an op's holds keep it
    /// allocated, so no other buffer has it meanwhile).
    pub(super) fn key(&self) -> usize {
        Arc::as_ptr(&self.imp) as *const () as usize
    }

    /// A share in the buffer's memory, keeping it allocated for as long as it lives.
    pub fn hold(&self) -> Hold {
        Hold {
            _memory: self.imp.clone(),
        }
    }

    /// The device address of the first element (a host address under the emulator).
    pub(super) fn addr(&self) -> u64 {
        match &*self.imp {
            BufferImp::Cpu(b) => b.addr(),
            BufferImp::Cuda { addr, .. } => *addr,
            BufferImp::Mapped { memory, .. } => memory.addr,
        }
    }

    /// The first `len` elements (clamped to the buffer's length) as a kernel argument.
    ///
    /// # Safety
    /// The view must be used only by launches that run while the memory is allocated, and in
    /// the device's order (see [`Binder`](super::plan::Binder), the one caller).
    pub(super) unsafe fn view_prefix<A: Access>(&self, len: u32) -> DevSlice<T, A> {
        let len = len.min(self.len() as u32);
        // SAFETY: `len` elements of this buffer from its start; the caller keeps its use in
        // the buffer's life.
        unsafe { DevSlice::from_raw_parts(self.addr(), len) }
    }
}

/// A group's arrays held as [`Buffer`]s on a device: `Group<Buffers>` for any group the
/// kernels declare with `device_data!`.
#[derive(Clone, Copy, Debug)]
pub struct Buffers;

impl Store for Buffers {
    type Array<T: Element, A: Access> = Buffer<T>;
}

/// A group's arrays read back to the host: `Group<Vecs>`.
#[derive(Clone, Copy, Debug)]
pub struct Vecs;

impl Store for Vecs {
    type Array<T: Element, A: Access> = Vec<T>;
}

/// Allocates a group's arrays, zeroed, on a device: `Group::<Buffers>::build(&mut device.zeroed(), ..)`;
/// or, from [`Device::zeroed_used`], only the arrays the group's access uses, each other
/// array with no element.
pub struct Zeroed<'d> {
    pub(super) device: &'d Device,
    pub(super) used_only: bool,
}

impl Build<Buffers> for Zeroed<'_> {
    type Error = Error;
    fn array<T: Element, A: Access>(
        &mut self,
        name: &'static str,
        len: usize,
    ) -> Result<Buffer<T>, Error> {
        let len = if self.used_only && A::USE == Use::Unused {
            0
        } else {
            len
        };
        Ok(self.device.alloc_zeroed(len)?.named(name))
    }
}

/// Reads a group's arrays back: `group.convert(&mut device.reader())`.
pub struct Reader<'d>(pub(super) &'d Device);

impl Convert<Buffers, Vecs> for Reader<'_> {
    type Error = Error;
    fn array<T: Element, In: Access, Out: Access>(
        &mut self,
        _: &'static str,
        array: &Buffer<T>,
    ) -> Result<Vec<T>, Error> {
        self.0.download(array)
    }
}

impl Device {
    /// A buffer of `len` zeroed elements.
    pub fn alloc_zeroed<T: Element>(&self, len: usize) -> Result<Buffer<T>, Error> {
        check_len::<T>(len)?;
        self.note_allocation::<T>(len);
        let imp = match &self.imp {
            Imp::Cpu(_) => BufferImp::Cpu(cpu::HostBuffer::zeroed(len)?),
            Imp::Cuda(gpu) => BufferImp::cuda(gpu.alloc_zeroed(len * size_of::<T>())?),
        };
        Ok(Buffer {
            imp: Arc::new(imp),
            device: self.id,
            name: std::any::type_name::<T>(),
            ringed: Arc::default(),
        })
    }

    /// A buffer of `len` zeroed elements that the host and the kernels share without copies:
    /// page-locked host memory mapped into the GPU's address space (plain host memory under
    /// the emulation). Kernels reach it across the bus, so it suits a few words a step. Its
    /// bytes are host memory, not counted as the device's. The host reaches it through a
    /// [`Ring`](super::Ring), or with [`Device::download`] and [`Device::write`], which wait for the GPU
    /// first.
    pub fn alloc_shared<T: Element>(&self, len: usize) -> Result<Buffer<T>, Error> {
        check_len::<T>(len)?;
        let imp = match &self.imp {
            Imp::Cpu(_) => BufferImp::Cpu(cpu::HostBuffer::zeroed(len)?),
            Imp::Cuda(gpu) => BufferImp::Mapped {
                memory: gpu.mapped(len * size_of::<T>())?,
                len,
                _element: PhantomData,
            },
        };
        Ok(Buffer {
            imp: Arc::new(imp),
            device: self.id,
            name: std::any::type_name::<T>(),
            ringed: Arc::default(),
        })
    }

    /// A buffer holding a copy of `data`.
    pub fn upload<T: Element>(&self, data: &[T]) -> Result<Buffer<T>, Error> {
        check_len::<T>(data.len())?;
        self.note_allocation::<T>(data.len());
        let imp = match &self.imp {
            Imp::Cpu(_) => BufferImp::Cpu(cpu::HostBuffer::from_slice(data)?),
            Imp::Cuda(gpu) => BufferImp::cuda(gpu.upload(data)?),
        };
        Ok(Buffer {
            imp: Arc::new(imp),
            device: self.id,
            name: std::any::type_name::<T>(),
            ringed: Arc::default(),
        })
    }

    /// Overwrites the start of `buffer` with `data`.
    pub fn write<T: Element>(&self, buffer: &mut Buffer<T>, data: &[T]) -> Result<(), Error> {
        if data.len() > buffer.len() {
            return Err(Error::Invalid(format!(
                "cannot write {} elements into a buffer of {}",
                data.len(),
                buffer.len()
            )));
        }
        buffer.device.check(self.id, "a buffer")?;
        buffer.check_writable()?;
        match (&self.imp, &*buffer.imp) {
            (Imp::Cpu(emu), BufferImp::Cpu(b)) => {
                let _order = emu.in_order();
                // SAFETY: in the device's order (no launch runs), and `&mut buffer` excludes
                // the other host borrows.
                let slice = unsafe { b.as_mut_slice() };
                slice[..data.len()].copy_from_slice(data);
                Ok(())
            }
            (Imp::Cuda(gpu), BufferImp::Cuda { bytes, .. }) => gpu.write(&mut locked(bytes), data),
            (Imp::Cuda(gpu), BufferImp::Mapped { memory, .. }) => {
                let sides = gpu.in_order();
                gpu.synchronize(&sides)?;
                // SAFETY: no kernel runs (waited for above, and none is queued while the
                // device's order is held), no other host access runs (each takes the order:
                // here, `download`, `zero`, a ring's), and the buffer holds at least
                // `data.len()` elements.
                unsafe {
                    let dst = memory.ptr.cast::<T>();
                    std::ptr::copy_nonoverlapping(data.as_ptr(), dst, data.len());
                }
                Ok(())
            }
            _ => unreachable!("a buffer of this device is of its backend"),
        }
    }

    /// Copies the whole buffer back to the host (waits for the work queued before).
    pub fn download<T: Element>(&self, buffer: &Buffer<T>) -> Result<Vec<T>, Error> {
        buffer.device.check(self.id, "a buffer")?;
        match (&self.imp, &*buffer.imp) {
            (Imp::Cpu(emu), BufferImp::Cpu(b)) => {
                let _order = emu.in_order();
                // SAFETY: in the device's order: no launch writes meanwhile.
                Ok(unsafe { b.as_slice() }.to_vec())
            }
            (Imp::Cuda(gpu), BufferImp::Cuda { bytes, .. }) => gpu.download(&locked(bytes)),
            (Imp::Cuda(gpu), BufferImp::Mapped { memory, len, .. }) => {
                let sides = gpu.in_order();
                gpu.synchronize(&sides)?;
                // SAFETY: as in `write`; `len` elements of plain bytes.
                Ok(unsafe { std::slice::from_raw_parts(memory.ptr.cast::<T>(), *len) }.to_vec())
            }
            _ => unreachable!("a buffer of this device is of its backend"),
        }
    }

    /// Sets every element of `buffer` to zero.
    pub fn zero<T: Element>(&self, buffer: &mut Buffer<T>) -> Result<(), Error> {
        buffer.device.check(self.id, "a buffer")?;
        buffer.check_writable()?;
        match (&self.imp, &*buffer.imp) {
            (Imp::Cpu(emu), BufferImp::Cpu(b)) => {
                let _order = emu.in_order();
                // SAFETY: as in `write`.
                unsafe { b.as_mut_slice() }.fill(T::zeroed());
                Ok(())
            }
            (Imp::Cuda(gpu), BufferImp::Cuda { bytes, .. }) => gpu.zero(&mut locked(bytes)),
            (Imp::Cuda(gpu), BufferImp::Mapped { memory, len, .. }) => {
                let sides = gpu.in_order();
                gpu.synchronize(&sides)?;
                // SAFETY: as in `write`.
                unsafe { std::ptr::write_bytes(memory.ptr.cast::<T>(), 0, *len) };
                Ok(())
            }
            _ => unreachable!("a buffer of this device is of its backend"),
        }
    }

    /// Copies `src` into the start of `dst`, device to device.
    pub fn copy<T: Element>(&self, src: &Buffer<T>, dst: &mut Buffer<T>) -> Result<(), Error> {
        if src.len() > dst.len() {
            return Err(Error::Invalid(format!(
                "cannot copy {} elements into a buffer of {}",
                src.len(),
                dst.len()
            )));
        }
        src.device.check(self.id, "a buffer")?;
        dst.device.check(self.id, "a buffer")?;
        dst.check_writable()?;
        match (&self.imp, &*src.imp, &*dst.imp) {
            (Imp::Cpu(emu), BufferImp::Cpu(s), BufferImp::Cpu(d)) => {
                let _order = emu.in_order();
                // SAFETY: as in `write`; two buffers are two allocations.
                unsafe { d.as_mut_slice()[..s.len()].copy_from_slice(s.as_slice()) };
                Ok(())
            }
            (
                Imp::Cuda(gpu),
                BufferImp::Cuda { bytes: s, .. },
                BufferImp::Cuda { bytes: d, .. },
            ) => gpu.copy(&locked(s), &mut locked(d)),
            (Imp::Cuda(_), BufferImp::Mapped { .. }, _)
            | (Imp::Cuda(_), _, BufferImp::Mapped { .. }) => Err(Error::Invalid(
                "a device copy to or from shared memory (download or write it instead)".into(),
            )),
            _ => unreachable!("a buffer of this device is of its backend"),
        }
    }
}
