//! Warp collectives: reductions and scans over the 32 lanes of a warp, the same bit for bit
//! on the GPU and on the CPU emulation.
//!
//! A collective takes each lane's value as a function of the lane, `value(lane)`, instead of a
//! value already in hand. On the GPU every lane evaluates `value` at its own lane and the
//! lanes exchange results with `shfl.sync` (butterflies for reductions, shifts up for scans).
//! On the CPU the emulator runs a block's threads one after the other, so no thread can wait
//! for another: there each calling thread evaluates `value` at all 32 lanes itself and
//! combines them in exactly the order the GPU's shuffles do. So:
//!
//! - `value` must be a pure function of the lane and of values that are the same in every
//!   lane of the warp (warp-uniform), reading only memory that nothing writes during the
//!   launch;
//! - every lane of the warp must call the collective, in the same order, with no lane
//!   returned early: kernels that use them launch whole warps (blocks are multiples of 32
//!   threads) and let lanes past the work take part with a neutral value;
//! - the combining operation must be commutative (`a ∘ b == b ∘ a` bit for bit: integer
//!   sums, float sums, minima of integers), so that both halves of each butterfly agree and
//!   every lane ends with the same result. Float sums are then a fixed tree, not a
//!   left-to-right fold: deterministic, though not the order of a sequential loop.
//!
//! The cost on the CPU is 32 evaluations per thread instead of one: collectives serve the
//! stages whose latency they cut (a warp instead of one thread, a strided sum instead of a
//! long loop), which are small.

use glam::Vec2;

/// Threads in a warp.
pub const WARP: u32 = 32;

/// Whether the calling thread may skip a kernel whose lanes other than 0 write nothing: on
/// the CPU, lane 0 evaluates every lane's values itself, so the other lanes' runs are copies
/// of its work. Always `false` on the GPU, where each lane's share is its own.
#[inline(always)]
pub fn is_copy_of_lane0(lane: u32) -> bool {
    cfg!(not(target_arch = "nvptx64")) && lane != 0
}

/// The butterfly distances of a reduction over a warp, in the order the GPU applies them.
const BUTTERFLY: [u32; 5] = [16, 8, 4, 2, 1];

/// A value the lanes of a warp can exchange: made of 32-bit words.
pub trait Exchanged: Copy {
    /// The value that lane `lane ^ mask` holds (GPU only).
    #[cfg(target_arch = "nvptx64")]
    fn shuffle_xor(self, mask: u32) -> Self;
}

/// A value a lane can hand to the other lanes of its [`Team`], word by word in registers.
pub trait Handed: Copy {
    /// The value that warp lane `source` holds, among the lanes `members` (GPU only).
    #[cfg(target_arch = "nvptx64")]
    fn shuffle_from(self, source: u32, members: u32) -> Self;
}

impl Exchanged for u32 {
    #[cfg(target_arch = "nvptx64")]
    #[inline(always)]
    fn shuffle_xor(self, mask: u32) -> Self {
        let out: u32;
        // SAFETY: every lane of the warp executes this shuffle (the module's contract), so
        // the full member mask is right; it reads registers only.
        unsafe {
            core::arch::asm!(
                "shfl.sync.bfly.b32 {out}, {value}, {mask}, 31, 0xffffffff;",
                out = out(reg32) out,
                value = in(reg32) self,
                mask = in(reg32) mask,
                options(nostack),
            );
        }
        out
    }
}

impl Handed for u32 {
    #[cfg(target_arch = "nvptx64")]
    #[inline(always)]
    fn shuffle_from(self, source: u32, members: u32) -> Self {
        let out: u32;
        // SAFETY: every lane named by `members` executes this shuffle (the team's contract);
        // it reads registers only.
        unsafe {
            core::arch::asm!(
                "shfl.sync.idx.b32 {out}, {value}, {source}, 31, {members};",
                out = out(reg32) out,
                value = in(reg32) self,
                source = in(reg32) source,
                members = in(reg32) members,
                options(nomem, nostack),
            );
        }
        out
    }
}

impl Handed for i32 {
    #[cfg(target_arch = "nvptx64")]
    #[inline(always)]
    fn shuffle_from(self, source: u32, members: u32) -> Self {
        (self as u32).shuffle_from(source, members) as i32
    }
}

impl Handed for u64 {
    #[cfg(target_arch = "nvptx64")]
    #[inline(always)]
    fn shuffle_from(self, source: u32, members: u32) -> Self {
        let low = (self as u32).shuffle_from(source, members);
        let high = ((self >> 32) as u32).shuffle_from(source, members);
        u64::from(high) << 32 | u64::from(low)
    }
}

impl Handed for i64 {
    #[cfg(target_arch = "nvptx64")]
    #[inline(always)]
    fn shuffle_from(self, source: u32, members: u32) -> Self {
        (self as u64).shuffle_from(source, members) as i64
    }
}

impl Handed for f32 {
    #[cfg(target_arch = "nvptx64")]
    #[inline(always)]
    fn shuffle_from(self, source: u32, members: u32) -> Self {
        f32::from_bits(self.to_bits().shuffle_from(source, members))
    }
}

impl Handed for Vec2 {
    #[cfg(target_arch = "nvptx64")]
    #[inline(always)]
    fn shuffle_from(self, source: u32, members: u32) -> Self {
        Vec2::new(
            self.x.shuffle_from(source, members),
            self.y.shuffle_from(source, members),
        )
    }
}

impl Exchanged for f32 {
    #[cfg(target_arch = "nvptx64")]
    #[inline(always)]
    fn shuffle_xor(self, mask: u32) -> Self {
        f32::from_bits(self.to_bits().shuffle_xor(mask))
    }
}

impl Exchanged for u64 {
    #[cfg(target_arch = "nvptx64")]
    #[inline(always)]
    fn shuffle_xor(self, mask: u32) -> Self {
        let low = (self as u32).shuffle_xor(mask);
        let high = ((self >> 32) as u32).shuffle_xor(mask);
        u64::from(high) << 32 | u64::from(low)
    }
}

impl Exchanged for Vec2 {
    #[cfg(target_arch = "nvptx64")]
    #[inline(always)]
    fn shuffle_xor(self, mask: u32) -> Self {
        Vec2::new(self.x.shuffle_xor(mask), self.y.shuffle_xor(mask))
    }
}

/// The value that lane `lane - delta` holds, or the lane's own for the first `delta` lanes.
#[cfg(target_arch = "nvptx64")]
#[inline(always)]
fn shuffle_up(value: u32, delta: u32) -> u32 {
    let out: u32;
    // SAFETY: every lane of the warp executes this shuffle (the module's contract), so the
    // full member mask is right; it reads registers only.
    unsafe {
        core::arch::asm!(
            "shfl.sync.up.b32 {out}, {value}, {delta}, 0, 0xffffffff;",
            out = out(reg32) out,
            value = in(reg32) value,
            delta = in(reg32) delta,
            options(nostack),
        );
    }
    out
}

/// `value(lane)` of all 32 lanes of the calling thread's warp combined by the commutative
/// `combine`, as a butterfly: the same result in every lane (see the module's contract).
#[inline(always)]
pub fn reduce<T: Exchanged>(lane: u32, value: impl Fn(u32) -> T, combine: impl Fn(T, T) -> T) -> T {
    #[cfg(target_arch = "nvptx64")]
    {
        let mut v = value(lane);
        for distance in BUTTERFLY {
            v = combine(v, v.shuffle_xor(distance));
        }
        v
    }
    #[cfg(not(target_arch = "nvptx64"))]
    {
        let mut v: [T; WARP as usize] = core::array::from_fn(|l| value(l as u32));
        for distance in BUTTERFLY {
            let before = v;
            for (l, slot) in v.iter_mut().enumerate() {
                *slot = combine(before[l], before[l ^ distance as usize]);
            }
        }
        v[lane as usize]
    }
}

/// A collective's `value` for a lane that already holds its own share, `mine`: on the GPU,
/// where each lane evaluates only its own, nothing is computed twice; where a thread cannot
/// ask another lane (the CPU emulation), the other lanes' shares are `theirs(l)`.
#[inline(always)]
pub fn own_or<T: Copy>(lane: u32, mine: T, theirs: impl Fn(u32) -> T) -> impl Fn(u32) -> T {
    move |l| if l == lane { mine } else { theirs(l) }
}

/// The wrapping sum of `value(lane)` over the warp's 32 lanes, in every lane.
#[inline(always)]
pub fn sum_u32(lane: u32, value: impl Fn(u32) -> u32) -> u32 {
    reduce(lane, value, u32::wrapping_add)
}

/// The wrapping sum of `value(lane)` over the warp's 32 lanes, for lane 0 only: on the CPU the
/// other lanes skip the work and get 0 (see [`is_copy_of_lane0`]), so only lane 0 may use it.
#[inline(always)]
pub fn sum_u32_in_lane0(lane: u32, value: impl Fn(u32) -> u32) -> u32 {
    if is_copy_of_lane0(lane) {
        0
    } else {
        sum_u32(lane, value)
    }
}

/// The sum of `value(lane)` over the warp's 32 lanes, in every lane: a fixed tree of float
/// additions, the same on every backend.
#[inline(always)]
pub fn sum_vec2(lane: u32, value: impl Fn(u32) -> Vec2) -> Vec2 {
    reduce(lane, value, |a, b| a + b)
}

/// The smallest `value(lane)` over the warp's 32 lanes, in every lane.
#[inline(always)]
pub fn min_u64(lane: u32, value: impl Fn(u32) -> u64) -> u64 {
    reduce(lane, value, u64::min)
}

/// The wrapping sum of `value(l)` over the lanes `l` before `lane` (an exclusive scan): each
/// lane gets its own.
#[inline(always)]
pub fn exclusive_sum_u32(lane: u32, value: impl Fn(u32) -> u32) -> u32 {
    #[cfg(target_arch = "nvptx64")]
    {
        let own = value(lane);
        inclusive_sum(lane, own).wrapping_sub(own)
    }
    #[cfg(not(target_arch = "nvptx64"))]
    {
        (0..lane).fold(0u32, |sum, l| sum.wrapping_add(value(l)))
    }
}

/// The wrapping sum of the lanes' `own` values up to and including `lane`'s (GPU only).
#[cfg(target_arch = "nvptx64")]
#[inline(always)]
fn inclusive_sum(lane: u32, own: u32) -> u32 {
    let mut inclusive = own;
    let mut distance = 1;
    while distance < WARP {
        let before = shuffle_up(inclusive, distance);
        if lane >= distance {
            inclusive = inclusive.wrapping_add(before);
        }
        distance *= 2;
    }
    inclusive
}

/// The exclusive prefix sums (wrapping) of a tile of `len` values, at most `WARP²`, from
/// `offset`: `store(i, offset + value(0) + … + value(i - 1))` for each `i < len`. Every
/// value is read before the first is stored, so `store` may overwrite what `value` reads.
///
/// On the GPU the warp takes the tile row by row, lane `l` element `l` of each row of
/// [`WARP`], so that each row is read and written in one coalesced access (where a lane
/// walking 32 elements of its own touches 32 lines an access), and the rows' sums cross the
/// lanes by shuffles: every lane must call it. On the CPU the calling thread walks the tile
/// in order by itself, so there only lane 0 may call it (see [`is_copy_of_lane0`]).
#[inline(always)]
pub fn exclusive_scan_tile(
    lane: u32,
    (len, offset): (u32, u32),
    value: impl Fn(u32) -> u32,
    mut store: impl FnMut(u32, u32),
) {
    #[cfg(target_arch = "nvptx64")]
    {
        let at = |row: usize| row as u32 * WARP + lane;
        let values: [u32; WARP as usize] = core::array::from_fn(|row| match at(row) < len {
            true => value(at(row)),
            false => 0,
        });
        // The rows' scans side by side, a shuffle distance at a time: 32 independent
        // shuffles in flight, where row after row waits on each (a small scan's warps are
        // one chain of them: `paper`'s step 4.6% slower on an H200).
        let mut inclusive = values;
        let mut distance = 1;
        while distance < WARP {
            for sum in &mut inclusive {
                let before = shuffle_up(*sum, distance);
                if lane >= distance {
                    *sum = sum.wrapping_add(before);
                }
            }
            distance *= 2;
        }
        // Each row's total, from its last lane: 32 independent shuffles in flight together,
        // where each row's offset waited for the shuffle of the row before. The offsets then
        // add up in registers, each step short enough for the loops to unroll whole: a loop
        // that took a row's shuffle and store a step was unrolled four times, not 32, and
        // its run-time row index put the rows in local memory.
        let totals: [u32; WARP as usize] =
            core::array::from_fn(|row| inclusive[row].shuffle_from(WARP - 1, u32::MAX));
        let mut running = offset;
        let starts: [u32; WARP as usize] = core::array::from_fn(|row| {
            let start = running.wrapping_add(inclusive[row].wrapping_sub(values[row]));
            running = running.wrapping_add(totals[row]);
            start
        });
        for (row, start) in starts.iter().enumerate() {
            if at(row) < len {
                store(at(row), *start);
            }
        }
    }
    #[cfg(not(target_arch = "nvptx64"))]
    {
        let _ = lane;
        let mut running = offset;
        for i in 0..len {
            let own = value(i);
            store(i, running);
            running = running.wrapping_add(own);
        }
    }
}

/// A team of `width` consecutive lanes of a warp (a power of two up to 32, aligned to its
/// width) that shares one body's work: each lane takes every `width`-th item, and what the
/// lanes find is handed to all of them in lane order, so that the team folds it exactly as
/// one thread walking the items in order would.
///
/// On the CPU the emulator cannot let one thread wait for another, so there lane 0 is the
/// whole team: it takes every item itself (a stride of 1) and the other lanes do nothing
/// (see [`Team::is_copy`]). Either way the result is that of the plain loop, bit for bit.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Team {
    /// The calling thread's place in the team.
    lane: u32,
    /// Lanes in the team.
    width: u32,
    /// The warp lane of the team's lane 0.
    first: u32,
}

impl Team {
    /// A team of one: the calling thread alone.
    pub const ALONE: Team = Team {
        lane: 0,
        width: 1,
        first: 0,
    };

    /// The team of `width` lanes (a power of two from 1 to 32) that the thread at `warp_lane`
    /// belongs to.
    #[inline(always)]
    pub fn new(warp_lane: u32, width: u32) -> Self {
        let lane = warp_lane % width;
        Team {
            lane,
            width,
            first: warp_lane - lane,
        }
    }

    /// How many lanes share the body: 1 for a body of one thread (on the CPU too, which
    /// runs a team's lanes as one thread).
    #[inline(always)]
    pub fn width(&self) -> u32 {
        self.width
    }

    /// The calling thread's place in the team, 0 to `width - 1`.
    #[inline(always)]
    pub fn lane(&self) -> u32 {
        self.lane
    }

    /// Whether the calling thread only repeats lane 0's work: the other lanes on the CPU,
    /// where lane 0 takes all the team's items. Never on the GPU.
    #[inline(always)]
    pub fn is_copy(&self) -> bool {
        is_copy_of_lane0(self.lane)
    }

    /// Whether the calling thread writes the team's results: lane 0.
    #[inline(always)]
    pub fn leads(&self) -> bool {
        self.lane == 0
    }

    /// The calling thread's first item of `start .. end` and its distance to the next: on
    /// the GPU its lane and the team's width, on the CPU (lane 0 alone) 0 and 1.
    #[inline(always)]
    pub fn stride(&self) -> (u32, u32) {
        if cfg!(target_arch = "nvptx64") {
            (self.lane, self.width)
        } else {
            (0, 1)
        }
    }

    /// Team lane `from`'s `value`, in every lane; on the CPU, where lane 0 is the whole team
    /// (`from` is then 0), its own.
    #[inline(always)]
    pub fn share<R: Handed>(&self, value: R, from: u32) -> R {
        #[cfg(target_arch = "nvptx64")]
        {
            value.shuffle_from(self.first + from, self.members())
        }
        #[cfg(not(target_arch = "nvptx64"))]
        {
            let _ = from;
            value
        }
    }

    /// Gives `fold` every lane's `found` value that is `Some`, in lane order, in every lane:
    /// one step of a walk over items taken [`Team::stride`] by stride.
    #[inline(always)]
    pub fn fold_found<R: Handed + Default>(&self, found: Option<R>, mut fold: impl FnMut(R)) {
        #[cfg(target_arch = "nvptx64")]
        if self.width > 1 {
            let mut rest = self.ballot(found.is_some());
            let value = found.unwrap_or_default();
            while rest != 0 {
                let from = rest.trailing_zeros();
                rest &= rest - 1;
                fold(self.share(value, from));
            }
            return;
        }
        if let Some(value) = found {
            fold(value);
        }
    }

    /// Every lane's `value` merged into one, in every lane (a butterfly over the team's
    /// lanes). The lanes merge in different orders, so `merge` must be associative and
    /// commutative (integer sums, a least key) for them to agree, and then the result is
    /// what one thread merging the values in any order would get. On the CPU, where lane 0
    /// holds the whole team's value, `value` itself.
    #[inline(always)]
    pub fn merge<R: Handed>(&self, value: R, merge: impl Fn(R, R) -> R) -> R {
        #[cfg(target_arch = "nvptx64")]
        {
            let mut value = value;
            let mut distance = 1;
            while distance < self.width {
                let other = value.shuffle_from(self.first + (self.lane ^ distance), self.members());
                value = merge(value, other);
                distance *= 2;
            }
            value
        }
        #[cfg(not(target_arch = "nvptx64"))]
        {
            let _ = merge;
            value
        }
    }

    /// The team's lanes as a warp's member mask.
    #[cfg(target_arch = "nvptx64")]
    #[inline(always)]
    fn members(&self) -> u32 {
        (u32::MAX >> (WARP - self.width)) << self.first
    }

    /// Bit `l` set where team lane `l` has `p` true.
    #[cfg(target_arch = "nvptx64")]
    #[inline(always)]
    fn ballot(&self, p: bool) -> u32 {
        let all: u32;
        // SAFETY: every lane of the team executes this vote (the team's contract), and the
        // member mask names exactly those lanes; it reads registers only.
        unsafe {
            core::arch::asm!(
                "{{ .reg .pred p; setp.ne.u32 p, {p}, 0; vote.sync.ballot.b32 {out}, p, {members}; }}",
                out = out(reg32) all,
                p = in(reg32) u32::from(p),
                members = in(reg32) self.members(),
                options(nomem, nostack),
            );
        }
        (all >> self.first) & (u32::MAX >> (WARP - self.width))
    }
}
