//! Steps in flight: each step's input goes up and its output comes back through page-locked
//! host memory, queued on the device's stream behind the step itself, so the host never
//! waits for a step it has just queued. It reads each step's output a few steps later, when
//! the ring is full or it drains it.

use std::collections::VecDeque;
use std::marker::PhantomData;

use super::cuda::{Fence, Pinned};
use super::{Buffer, Device, Element, Error, Imp};

/// A ring of `depth` steps in flight, each with one input `I` and one output `O`.
pub struct Ring<I: Element, O: Element> {
    depth: usize,
    staging: Staging,
    /// Slots in flight, oldest first.
    in_flight: VecDeque<usize>,
    /// Steps queued so far.
    queued: u64,
    /// The outputs as read back, by slot.
    outputs: Vec<O>,
    _inputs: PhantomData<I>,
}

enum Staging {
    /// The emulation runs each step before it returns: plain memory, nothing to wait for.
    Host,
    /// Pinned copies of `inputs` and `outputs`, and one fence per slot.
    Pinned {
        inputs: Pinned,
        outputs: Pinned,
        fences: Vec<Fence>,
    },
}

impl Device {
    /// A ring of `depth` (at least 1) steps in flight. Depth 1 waits for every step.
    pub fn ring<I: Element, O: Element>(&self, depth: usize) -> Result<Ring<I, O>, Error> {
        if depth == 0 {
            return Err(Error::Invalid(
                "a ring of depth 0 (allowed: 1 or more)".into(),
            ));
        }
        let staging = match &self.imp {
            Imp::Cpu(_) => Staging::Host,
            Imp::Cuda(gpu) => Staging::Pinned {
                inputs: gpu.pinned(depth * size_of::<I>())?,
                outputs: gpu.pinned(depth * size_of::<O>())?,
                fences: (0..depth)
                    .map(|_| gpu.fence(false))
                    .collect::<Result<_, _>>()?,
            },
        };
        Ok(Ring {
            depth,
            staging,
            in_flight: VecDeque::with_capacity(depth),
            queued: 0,
            outputs: vec![O::zeroed(); depth],
            _inputs: PhantomData,
        })
    }
}

impl<I: Element, O: Element> Ring<I, O> {
    /// The slot of the next step.
    fn slot(&self) -> usize {
        (self.queued % self.depth as u64) as usize
    }

    /// Makes room for one more step: with `depth` steps in flight, waits for the oldest and
    /// returns its output.
    pub fn reserve(&mut self) -> Result<Option<O>, Error> {
        if self.in_flight.len() < self.depth {
            return Ok(None);
        }
        self.oldest()
    }

    /// Queues the copy of `input` into element 0 of `dst`, for the step about to be queued
    /// (call [`Ring::reserve`] first).
    pub fn send(&mut self, device: &Device, input: I, dst: &Buffer<I>) -> Result<(), Error> {
        self.check_room()?;
        let slot = self.slot();
        if dst.is_empty() {
            return Err(Error::Invalid("sending into an empty buffer".into()));
        }
        match (&self.staging, &device.imp) {
            (Staging::Host, Imp::Cpu(emu)) => {
                let _order = emu.in_order();
                // SAFETY: element 0 of a live host buffer, in the device's order.
                unsafe { (dst.addr() as *mut I).write(input) };
                Ok(())
            }
            (Staging::Pinned { inputs, .. }, Imp::Cuda(gpu)) => {
                let at = inputs.ptr.cast::<I>().wrapping_add(slot);
                // SAFETY: the slot is not in flight (checked), so no queued copy reads it;
                // the copy queued below reads it before the slot's fence, which is waited
                // for before the slot is written again.
                unsafe {
                    at.write_unaligned(input);
                    gpu.upload_async(at.cast(), dst.addr(), size_of::<I>())
                }
            }
            _ => Err(Error::Invalid("a ring of another backend".into())),
        }
    }

    /// After the step is queued: queues the copy of element 0 of `src` back to the host,
    /// and the step's fence.
    pub fn receive(&mut self, device: &Device, src: &Buffer<O>) -> Result<(), Error> {
        self.check_room()?;
        let slot = self.slot();
        if src.is_empty() {
            return Err(Error::Invalid("receiving from an empty buffer".into()));
        }
        match (&mut self.staging, &device.imp) {
            (Staging::Host, Imp::Cpu(emu)) => {
                let _order = emu.in_order();
                // SAFETY: element 0 of a live host buffer, in the device's order.
                self.outputs[slot] = unsafe { (src.addr() as *const O).read() };
            }
            (
                Staging::Pinned {
                    outputs, fences, ..
                },
                Imp::Cuda(gpu),
            ) => {
                let at = outputs.ptr.cast::<O>().wrapping_add(slot);
                // SAFETY: nothing reads the slot until its fence, recorded after the copy,
                // has been waited for.
                unsafe { gpu.download_async(src.addr(), at.cast(), size_of::<O>())? };
                gpu.record(&mut fences[slot])?;
            }
            _ => return Err(Error::Invalid("a ring of another backend".into())),
        }
        self.in_flight.push_back(slot);
        self.queued += 1;
        Ok(())
    }

    /// Waits for the oldest step in flight and returns its output (`None` when none is).
    pub fn oldest(&mut self) -> Result<Option<O>, Error> {
        let Some(slot) = self.in_flight.pop_front() else {
            return Ok(None);
        };
        if let Staging::Pinned {
            outputs, fences, ..
        } = &self.staging
        {
            fences[slot].wait()?;
            // SAFETY: the copy into the slot is done (its fence has passed).
            self.outputs[slot] = unsafe { outputs.ptr.cast::<O>().add(slot).read_unaligned() };
        }
        Ok(Some(self.outputs[slot]))
    }

    fn check_room(&self) -> Result<(), Error> {
        if self.in_flight.len() >= self.depth {
            return Err(Error::Invalid(format!(
                "{} steps in flight in a ring of depth {}: reserve first",
                self.in_flight.len(),
                self.depth
            )));
        }
        Ok(())
    }
}

impl<I: Element, O: Element> Drop for Ring<I, O> {
    fn drop(&mut self) {
        // The pinned memory must outlive the copies still queued into it.
        if let Staging::Pinned { fences, .. } = &self.staging {
            for &slot in &self.in_flight {
                let _ = fences[slot].wait();
            }
        }
    }
}
