//! Every kernel entry point, listed once.
//!
//! `kernels!` turns each line into a typed [`Kernel`] constant for the host, an entry in
//! [`ALL`], and, on nvptx, the `extern "ptx-kernel"` entry point that calls the body. Because
//! the entry's name and the constant's `name` come from the same identifier, they cannot drift.

use crate::access::Read;
use crate::exec::Cooperative;
use crate::game::{ai, autopilot, effects, master};
use crate::math;
use crate::persistent::{self, ProgramArgs, Runner, Stage};
use crate::primitives::{histogram, scan, sort, touch};
use crate::render::{self, camera, particles, radar, still};
use crate::rng::streams;
use crate::sim::{broad, contact, free_list, integrate, narrow, renumber, scatter};
use crate::{DevSlice, Kernel, KernelInfo};

macro_rules! kernels {
    (@wait) => {
        crate::exec::follow_previous_launch()
    };
    // The body waits itself (see `follow_previous_launch`).
    (@wait waits) => {};
    (@reads) => {
        false
    };
    (@reads waits) => {
        true
    };
    ($(
        $(#[doc = $doc:literal])+
        $konst:ident = $entry:ident($args:ty) => $body:path $(, $waits:ident)?;
    )*) => {
        $(
            $(#[doc = $doc])+
            pub const $konst: Kernel<$args> = Kernel {
                name: stringify!($entry),
                body: $body,
                block: {
                    fn block(block: u32, block_dim: u32, grid_dim: u32, args: &$args) {
                        crate::exec::run_block($body, block, block_dim, grid_dim, args)
                    }
                    block
                },
            };
        )*

        /// Every kernel of the module, in declaration order.
        pub const ALL: &[KernelInfo] = &[
            $(KernelInfo {
                name: stringify!($entry),
                summary: concat!($($doc),+),
                reads_before_waiting: kernels!(@reads $($waits)?),
            }),*
        ];

        /// The PTX entry points: one per kernel, each a call of its body (not in the
        /// persistent step's module).
        #[cfg(all(target_arch = "nvptx64", not(gpuwars_program)))]
        mod entries {
            use super::*;
            $(
                #[unsafe(no_mangle)]
                /// Entry point (see the constant of the same name in upper case).
                pub unsafe extern "ptx-kernel" fn $entry(args: $args) {
                    kernels!(@wait $($waits)?);
                    $body(crate::Thread::current(), &args)
                }
            )*
        }
    };
}

kernels! {
    /// Sums each tile of a u32 array (first half of a prefix-sum pass).
    SCAN_REDUCE = scan_reduce(scan::ReduceArgs) => scan::reduce_tiles;
    /// Exclusive prefix sums inside each tile, from the tile's offset.
    SCAN_TILES = scan_tiles(scan::ScanArgs) => scan::scan_tiles;
    /// Exclusive prefix sums inside each tile, from the sum of the tiles before it.
    SCAN_TILES_AFTER_SUMS = scan_tiles_after_sums(scan::ScanArgs) => scan::scan_tiles_after_sums;
    /// Counts keys per bin with atomic adds.
    HISTOGRAM = histogram(histogram::HistogramArgs) => histogram::count_keys;
    /// Adds one to each thread's element: the launch floor's probe.
    TOUCH = touch(touch::TouchArgs) => touch::touch;
    /// Counts the `f32`s of a range whose fast reciprocal square root differs from the
    /// correctly rounded one's (the check of `math::recip_sqrt`).
    CHECK_RECIP_SQRT = check_recip_sqrt(math::RecipSqrtCheckArgs) => math::check_recip_sqrt;
    /// The contact geometry's verdict on each of a list of motions (a check against the CPU's
    /// and a reference's).
    SWEEP_CASES = sweep_cases(contact::SweepCasesArgs) => contact::sweep_cases;
    /// Rounds of one touch a thread with a block barrier between them: the one-block floor.
    TOUCH_ROUNDS = touch_rounds(touch::TouchRoundsArgs) => touch::touch_rounds;
    /// Counts the digits of each tile of keys (one counting-sort pass).
    SORT_COUNT = sort_count(sort::CountArgs) => sort::count_digits;
    /// Moves each tile's (key, index) pairs to their sorted slots (one counting-sort pass).
    SORT_SCATTER = sort_scatter(sort::ScatterArgs) => sort::scatter_digits;
    /// Keys every live body by its (cell, kind) bucket and counts the buckets (atomics).
    COUNT_CELLS = count_cells(broad::CountArgs) => broad::count_cells;
    /// Writes every live body into its bucket, in arrival order. It reads the count's keys
    /// and ranks before it waits for the scan.
    PLACE_IN_CELLS = place_in_cells(broad::PlaceArgs) => broad::place_in_cells, waits;
    /// Puts every bucket in increasing slot order.
    ORDER_CELLS = order_cells(broad::OrderArgs) => broad::order_cells;
    /// Merges the sorted runs of large buckets in pairs (a bounded grid's ordering).
    MERGE_RUNS = merge_runs(broad::MergeArgs) => broad::merge_runs;
    /// Copies each body bound for a new slot (the grid's order within its kind's range)
    /// into the renumbering's buffers.
    GATHER_IN_CELL_ORDER = gather_in_cell_order(renumber::RenumberArgs) => renumber::gather_in_cell_order;
    /// Each slot takes the body gathered for it, or is free; the grid's entries name the new
    /// slots.
    SETTLE_IN_CELL_ORDER = settle_in_cell_order(renumber::RenumberArgs) => renumber::settle_in_cell_order;
    /// Narrow phase: each body's collision response to its neighbours, and energy losses.
    COLLIDE = collide(narrow::CollideArgs) => narrow::collide;
    /// The narrow phase for worlds of circles only (no rectangle tests).
    COLLIDE_CIRCLES = collide_circles(narrow::CollideArgs) => narrow::collide_circles;
    /// The narrow phase for worlds with swept pairs (contacts found over each motion).
    COLLIDE_SWEPT = collide_swept(narrow::CollideArgs) => narrow::collide_swept;
    /// The narrow phase for worlds of circles only with swept pairs.
    COLLIDE_CIRCLES_SWEPT = collide_circles_swept(narrow::CollideArgs) => narrow::collide_circles_swept;
    /// [`COLLIDE`] that logs every contact it counts (audit runs).
    COLLIDE_LOGGED = collide_logged(narrow::CollideArgs) => narrow::collide_logged;
    /// [`COLLIDE_CIRCLES`] that logs every contact it counts (audit runs).
    COLLIDE_CIRCLES_LOGGED = collide_circles_logged(narrow::CollideArgs) => narrow::collide_circles_logged;
    /// [`COLLIDE_SWEPT`] that logs every contact it counts (audit runs).
    COLLIDE_SWEPT_LOGGED = collide_swept_logged(narrow::CollideArgs) => narrow::collide_swept_logged;
    /// [`COLLIDE_CIRCLES_SWEPT`] that logs every contact it counts (audit runs).
    COLLIDE_CIRCLES_SWEPT_LOGGED = collide_circles_swept_logged(narrow::CollideArgs) => narrow::collide_circles_swept_logged;
    /// Euler integration, the boundary rule, and deaths.
    INTEGRATE = integrate(integrate::IntegrateArgs) => integrate::integrate;
    /// Flags the free usable slots (first step of rebuilding the free lists).
    MARK_FREE = mark_free(free_list::MarkArgs) => free_list::mark_free;
    /// Writes each kind's free slots in order, and their counts.
    GATHER_FREE = gather_free(free_list::GatherArgs) => free_list::gather_free;
    /// Flags the free usable slots and writes each kind's free slots and counts, in one
    /// launch (worlds of small ranges). It reads its slots' kinds and ranges before it waits
    /// for the launch before it.
    MARK_AND_GATHER_FREE = mark_and_gather_free(free_list::MarkGatherArgs) => free_list::mark_and_gather_free, waits;
    /// Brings bodies to life at random places from their slots' generators.
    SCATTER = scatter(scatter::ScatterArgs) => scatter::scatter;
    /// The master before the physics: the step's input (the player's or the autopilot's),
    /// ship, shots, spawn counts (one warp).
    MASTER = master(master::MasterArgs) => master::master;
    /// The autopilot: the ship's input for the next step, from the step's grid as it was
    /// built (its entries' places and velocities), beside the rest of the step (one warp).
    AUTOPILOT = autopilot(autopilot::AutopilotArgs) => autopilot::autopilot;
    /// Explosions: kills burst into particles, the others move and fade.
    BURST_AND_FADE = burst_and_fade(effects::EffectsArgs) => effects::burst_and_fade;
    /// The master after the physics: score, counts, FPS meter, game over (one warp).
    TALLY = tally(master::TallyArgs) => master::tally;
    /// Brings the enemies the master thread ordered to life at random places.
    BIRTHS = births(master::BirthArgs) => master::births;
    /// Brings the enemies the master thread ordered to life at random places, and counts
    /// every slot into the grid's buckets (the broad phase's first launch, in small games).
    /// It reads its slots' kinds and free-list flags before it waits for the master.
    BIRTHS_AND_COUNT = births_and_count(master::BirthCountArgs) => master::births_and_count, waits;
    /// The enemies' machines, every live enemy in grid order: perceive, transition, steer.
    THINK = think(ai::ThinkArgs) => ai::think;
    /// The enemies' machines with teams of threads for the bodies that expect many
    /// neighbours.
    THINK_IN_TEAMS = think_in_teams(ai::ThinkArgs) => ai::think_in_teams;
    /// The narrow phase without rectangles, the enemies' machines and the integrator in one
    /// launch, with teams of threads (worlds small enough for teams). It finds its slot
    /// before it waits for the launch before it.
    COLLIDE_THINK_INTEGRATE = collide_think_integrate(ai::BodyStepArgs) => ai::collide_think_integrate, waits;
    /// [`COLLIDE_THINK_INTEGRATE`] for worlds with swept pairs. It finds its slot before it
    /// waits for the launch before it.
    COLLIDE_THINK_INTEGRATE_SWEPT = collide_think_integrate_swept(ai::BodyStepArgs) => ai::collide_think_integrate_swept, waits;
    /// [`COLLIDE_THINK_INTEGRATE`] that logs every contact it counts (audit runs).
    COLLIDE_THINK_INTEGRATE_LOGGED = collide_think_integrate_logged(ai::BodyStepArgs) => ai::collide_think_integrate_logged, waits;
    /// [`COLLIDE_THINK_INTEGRATE_SWEPT`] that logs every contact it counts (audit runs).
    COLLIDE_THINK_INTEGRATE_SWEPT_LOGGED = collide_think_integrate_swept_logged(ai::BodyStepArgs) => ai::collide_think_integrate_swept_logged, waits;
    /// Sets up every slot's generator from its seed and the parameter table.
    SEED_STREAMS = seed_streams(streams::SeedArgs) => streams::seed_streams;
    /// Points the camera: the frame's view from the ship's position (one thread), for the
    /// GL renderer's vertices and for large worlds' kernel frames.
    CAMERA = camera(camera::CameraArgs) => camera::camera;
    /// Counts sampled bodies per radar pixel (atomic adds and maxima: order-free), for the
    /// GL renderer's radar.
    RADAR_BODIES = radar_bodies(radar::RadarArgs) => radar::radar_bodies;
    /// Writes the radar's pixels into an image of their own, and clears its counts.
    RADAR_IMAGE = radar_image(radar::RadarImageArgs) => radar::radar_image;
    /// Works the frame's camera out (in every thread, in worlds of up to
    /// `render::FOLD_CAMERA_SLOTS` slots), counts the radar's samples, and draws every live
    /// body's shape into the pixel keys (atomic maximum: order-free).
    SPLAT_BODIES = splat_bodies(render::FirstSplatArgs) => render::splat_bodies;
    /// Draws the bodies too large for one thread, 128 threads each (after splat_bodies).
    SPLAT_LARGE = splat_large(render::SplatArgs) => render::splat_large;
    /// Draws every shown particle's disc into the pixel keys, under the bodies (atomic
    /// maximum: order-free).
    SPLAT_PARTICLES = splat_particles(particles::ParticleSplatArgs) => particles::splat_particles;
    /// Turns each pixel's key into its colour (or the backdrop's) and clears the key.
    RESOLVE_PIXELS = resolve_pixels(render::ResolveArgs) => render::resolve_pixels;
    /// Copies what the renderers read of the world into the still a frame beside the next
    /// step draws from.
    KEEP_STILL = keep_still(still::StillArgs) => still::keep_still;
    /// Writes every slot's vertex for the GL renderer (into its mapped vertex buffer).
    WRITE_VERTICES = write_vertices(render::VertexArgs) => render::write_vertices;
    /// Writes every particle's vertex for the GL renderer, after the bodies'.
    WRITE_PARTICLE_VERTICES = write_particle_vertices(particles::ParticleVertexArgs) => particles::write_particle_vertices;
}

macro_rules! stages {
    ($($konst:ident),* $(,)?) => {
        /// The kernels a persistent step can run as stages ([`persistent::Stage::kernel`]
        /// is an index here): every kernel of a step's plans, and the launch floor's touch.
        pub const STAGES: &[&str] = &[$($konst.name),*];

        /// Runs `stage` (its kernel's body, with the argument struct it finds in `blob`)
        /// for the virtual threads `runner` holds; a stage naming no kernel of [`STAGES`]
        /// is a kernel fault.
        #[inline(always)]
        pub fn run_stage(stage: &Stage, blob: &DevSlice<u64, Read>, runner: &impl Runner) {
            let mut index = 0;
            $(
                if stage.kernel == index {
                    // A function of its own on the GPU, called once a stage: ptxas gives
                    // each stage the registers it needs alone, as its launch had, rather
                    // than one allocation across every stage's body in which each carries
                    // the others' spills (docs/pipeline.md, "The persistent step").
                    #[cfg_attr(target_arch = "nvptx64", inline(never))]
                    fn stage_of<R: Runner>(
                        stage: &Stage,
                        blob: &DevSlice<u64, Read>,
                        runner: &R,
                    ) {
                        // The body itself, not a closure around it: a closure is not
                        // inlined where LLVM finds it large, and a call a virtual thread
                        // spills what the call keeps live.
                        runner.run(stage, blob, $konst.body)
                    }
                    return stage_of(stage, blob, runner);
                }
                index += 1;
            )*
            crate::exec::no_such_stage(stage.kernel, index)
        }
    };
}

stages! {
    TOUCH,
    SCAN_REDUCE,
    SCAN_TILES,
    SCAN_TILES_AFTER_SUMS,
    COUNT_CELLS,
    PLACE_IN_CELLS,
    ORDER_CELLS,
    MERGE_RUNS,
    GATHER_IN_CELL_ORDER,
    SETTLE_IN_CELL_ORDER,
    COLLIDE,
    COLLIDE_CIRCLES,
    COLLIDE_SWEPT,
    COLLIDE_CIRCLES_SWEPT,
    COLLIDE_LOGGED,
    COLLIDE_CIRCLES_LOGGED,
    COLLIDE_SWEPT_LOGGED,
    COLLIDE_CIRCLES_SWEPT_LOGGED,
    INTEGRATE,
    MARK_FREE,
    GATHER_FREE,
    MARK_AND_GATHER_FREE,
    MASTER,
    AUTOPILOT,
    BURST_AND_FADE,
    TALLY,
    BIRTHS,
    BIRTHS_AND_COUNT,
    THINK,
    THINK_IN_TEAMS,
    COLLIDE_THINK_INTEGRATE,
    COLLIDE_THINK_INTEGRATE_SWEPT,
    COLLIDE_THINK_INTEGRATE_LOGGED,
    COLLIDE_THINK_INTEGRATE_SWEPT_LOGGED,
}

/// The persistent step: a program of stages, each a launch of [`STAGES`], with a barrier
/// across the grid between them (a cooperative launch; see [`persistent`]).
pub const PROGRAM: Cooperative<ProgramArgs> = Cooperative {
    name: "program",
    block: {
        #[cfg(not(target_arch = "nvptx64"))]
        fn block(
            block: u32,
            block_dim: u32,
            grid_dim: u32,
            args: &ProgramArgs,
            wait: &(dyn Fn() + Sync),
        ) {
            let runner = persistent::OnCpu {
                block,
                block_dim,
                grid_dim,
                wait,
            };
            persistent::program(&runner, args, run_stage)
        }
        #[cfg(target_arch = "nvptx64")]
        fn block(_: u32, _: u32, _: u32, _: &ProgramArgs, _: &(dyn Fn() + Sync)) {}
        block
    },
};

/// Every cooperative kernel: the entry points of the persistent step's module.
pub const COOPERATIVE: &[KernelInfo] = &[KernelInfo {
    name: PROGRAM.name,
    summary: "The persistent step: a program of the step's launches, with a barrier across \
              the grid between them.",
    reads_before_waiting: false,
}];

/// The persistent step's PTX entry point, alone in a module of its own.
#[cfg(all(target_arch = "nvptx64", gpuwars_program))]
#[unsafe(no_mangle)]
pub unsafe extern "ptx-kernel" fn program(args: ProgramArgs) {
    let runner = persistent::OnGpu {
        thread: crate::Thread::current(),
        barrier: args.barrier,
    };
    persistent::program(&runner, &args, run_stage)
}
