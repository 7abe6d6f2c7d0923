//! Steps in flight: each step's input goes up and its output comes back through memory that
//! the host and the kernels share ([`Device::alloc_shared`]: page-locked host memory mapped
//! into the GPU's address space), one element per step in flight, so no copy is queued
//! between two steps and the host never waits for a step it has just queued. Step `n` uses
//! element `n % depth` of both buffers (`n` counted modulo 2³², as the kernels count it); the
//! kernels find it with their own count of the steps begun. The host reads each step's
//! output a few steps later, when the ring is full or it drains it.

use std::collections::VecDeque;
use std::sync::Arc;
use std::sync::atomic::{AtomicBool, Ordering};

use super::cuda::Fence;
use super::{Buffer, BufferImp, Device, DeviceId, Element, Error, Imp};

/// A ring of steps in flight, each with one input `I` and one output `O`.
pub struct Ring<I: Element, O: Element> {
    /// Shares in the two buffers' memory (held, so it outlives the ring).
    inputs: Arc<BufferImp<I>>,
    outputs: Arc<BufferImp<O>>,
    /// The buffers' marks that a ring owns their host side (see `Buffer::ringed`), set
    /// while the ring exists.
    owned: [Arc<AtomicBool>; 2],
    depth: usize,
    /// One fence per slot on the GPU, recorded after its step; none under the emulation,
    /// which runs each step before it returns.
    fences: Vec<Fence>,
    /// Slots in flight, oldest first.
    in_flight: VecDeque<usize>,
    /// Steps queued so far.
    queued: u64,
    /// The device whose steps it holds.
    device: DeviceId,
    /// The outputs as read back, by slot.
    outputs_read: Vec<O>,
}

impl Device {
    /// A ring over `inputs` and `outputs`, buffers of [`Device::alloc_shared`] of one length
    /// (at least 1): the steps in flight. The kernels of each step read its input at, and
    /// write its output to, the slot of their own count of the steps, which starts at zero
    /// as the ring's does. Depth 1 waits for every step. While the ring exists it owns the
    /// buffers' host side: [`Device::write`], [`Device::zero`] and [`Device::copy`] into
    /// them are refused, and so is a second ring over either.
    pub fn ring<I: Element, O: Element>(
        &self,
        inputs: &Buffer<I>,
        outputs: &Buffer<O>,
    ) -> Result<Ring<I, O>, Error> {
        inputs.device().check(self.id, "a ring's buffer")?;
        outputs.device().check(self.id, "a ring's buffer")?;
        let depth = inputs.len();
        if depth == 0 || outputs.len() != depth {
            return Err(Error::Invalid(format!(
                "a ring of {depth} inputs and {} outputs (allowed: as many of each, 1 or more)",
                outputs.len()
            )));
        }
        let fences = match (&self.imp, &*inputs.imp, &*outputs.imp) {
            (Imp::Cpu(_), BufferImp::Cpu(_), BufferImp::Cpu(_)) => Vec::new(),
            (Imp::Cuda(gpu), BufferImp::Mapped { .. }, BufferImp::Mapped { .. }) => (0..depth)
                .map(|_| gpu.fence(false))
                .collect::<Result<_, _>>()?,
            _ => {
                return Err(Error::Invalid(
                    "a ring over buffers that are not this device's shared memory".into(),
                ));
            }
        };
        let owned = [inputs.ringed.clone(), outputs.ringed.clone()];
        if Arc::ptr_eq(&owned[0], &owned[1]) {
            return Err(Error::Invalid(
                "a ring over one buffer as its inputs and its outputs".into(),
            ));
        }
        claim(&owned[0], inputs.name())?;
        if let Err(e) = claim(&owned[1], outputs.name()) {
            owned[0].store(false, Ordering::Release);
            return Err(e);
        }
        Ok(Ring {
            inputs: inputs.imp.clone(),
            outputs: outputs.imp.clone(),
            owned,
            depth,
            fences,
            in_flight: VecDeque::with_capacity(depth),
            queued: 0,
            device: self.id,
            outputs_read: vec![O::zeroed(); depth],
        })
    }
}

/// Marks a buffer (`name`) as a ring's (see `Buffer::ringed`), unless another ring has it.
fn claim(ringed: &AtomicBool, name: &str) -> Result<(), Error> {
    ringed
        .compare_exchange(false, true, Ordering::AcqRel, Ordering::Acquire)
        .map(drop)
        .map_err(|_| Error::Invalid(format!("buffer `{name}` is another ring's already")))
}

impl<I: Element, O: Element> Drop for Ring<I, O> {
    fn drop(&mut self) {
        for owned in &self.owned {
            owned.store(false, Ordering::Release);
        }
    }
}

/// The host address of element `slot` of a shared buffer.
fn host_ptr<T: Element>(buffer: &BufferImp<T>, slot: usize) -> *mut T {
    let base = match buffer {
        BufferImp::Cpu(b) => b.addr() as *mut T,
        BufferImp::Mapped { memory, .. } => memory.ptr.cast::<T>(),
        // `Device::ring` takes no other kind.
        BufferImp::Cuda { .. } => unreachable!("a ring over device memory"),
    };
    base.wrapping_add(slot)
}

impl<I: Element, O: Element> Ring<I, O> {
    /// Steps queued through the ring so far.
    pub fn queued(&self) -> u64 {
        self.queued
    }

    /// Steps the ring holds in flight.
    pub fn depth(&self) -> usize {
        self.depth
    }

    /// The slot of the next step: its count modulo 2³², as the kernels keep it.
    fn slot(&self) -> usize {
        (self.queued as u32 as usize) % self.depth()
    }

    /// Makes room for one more step: with `depth` steps in flight, waits for the oldest and
    /// returns its output.
    pub fn reserve(&mut self, device: &Device) -> Result<Option<O>, Error> {
        if self.in_flight.len() < self.depth() {
            return Ok(None);
        }
        self.oldest(device)
    }

    /// Writes `input` into the slot of the step about to be queued (call [`Ring::reserve`]
    /// first).
    pub fn send(&mut self, device: &Device, input: I) -> Result<(), Error> {
        self.check(device)?;
        let at = host_ptr(&self.inputs, self.slot());
        match &device.imp {
            Imp::Cpu(emu) => {
                let _order = emu.in_order();
                // SAFETY: an element of a live host buffer, in the device's order.
                unsafe { at.write_unaligned(input) };
            }
            Imp::Cuda(gpu) => {
                let _order = gpu.in_order();
                // SAFETY: the host side is the ring's alone (the device's writes refuse its
                // buffers while it exists), and other host accesses of mapped memory take the
                // device's order (held). No kernel reads the slot meanwhile: `check` refuses
                // a step past the depth, so the step that last read it has passed its fence
                // (`reserve` waited for it); a kernel finds its slot by its count of steps,
                // which a game checks against the ring's every step (`Game::queue`, and each
                // status as it is handed out);
                // and the step that reads it next is queued after this write (a launch sees
                // the host's writes made before it).
                unsafe { at.write_volatile(input) }
            }
        }
        Ok(())
    }

    /// After the step is queued: notes it in flight, behind the GPU's fence for its slot
    /// (under the emulation, where the step has run, its output is read now).
    pub fn receive(&mut self, device: &Device) -> Result<(), Error> {
        self.check(device)?;
        let slot = self.slot();
        match &device.imp {
            Imp::Cpu(emu) => {
                let _order = emu.in_order();
                // SAFETY: an element of a live host buffer, in the device's order.
                self.outputs_read[slot] = unsafe { host_ptr(&self.outputs, slot).read() };
            }
            Imp::Cuda(gpu) => gpu.record(&mut self.fences[slot])?,
        }
        self.in_flight.push_back(slot);
        self.queued += 1;
        Ok(())
    }

    /// Waits for the oldest step in flight and returns its output (`None` when none is).
    pub fn oldest(&mut self, device: &Device) -> Result<Option<O>, Error> {
        self.device.check(device.id, "a ring")?;
        let Some(slot) = self.in_flight.pop_front() else {
            return Ok(None);
        };
        if let (Some(fence), Imp::Cuda(gpu)) = (self.fences.get(slot), &device.imp) {
            fence.wait()?;
            let _order = gpu.in_order();
            // SAFETY: the step that writes the slot is done (its fence has passed), the next
            // one to write it is not queued before the slot is sent again, and other host
            // accesses of mapped memory take the device's order (held).
            self.outputs_read[slot] = unsafe { host_ptr(&self.outputs, slot).read_volatile() };
        }
        Ok(Some(self.outputs_read[slot]))
    }

    /// Checks that `device` is the ring's and that a step has room.
    fn check(&self, device: &Device) -> Result<(), Error> {
        self.device.check(device.id, "a ring")?;
        if self.in_flight.len() >= self.depth() {
            return Err(Error::Invalid(format!(
                "{} steps in flight in a ring of depth {}: reserve first",
                self.in_flight.len(),
                self.depth()
            )));
        }
        Ok(())
    }
}
