//! Generates the committed table of MT607 parameter sets (`data/mt607_params.txt`).
//!
//! dcmt's search takes about 0.15 s per parameter set, too slow for start-up, so the game
//! reads a table made once by this program:
//!
//! ```text
//! cargo run --release --example mt607_table -- --seed 4172 --count 4096 --out data/mt607_params.txt
//! ```
//!
//! It does what dcmt's `init_dc(seed)` followed by `get_mt_parameter_id(32, 607, id)` for
//! `id = 0, 1, …, count - 1` does. The `matrix_a` search must run in sequence (each id
//! continues the creator's random stream); the tempering masks depend on `matrix_a` alone and
//! are computed in parallel. The file is written atomically.

use std::fmt::Write;
use std::path::PathBuf;
use std::sync::mpsc;

use anyhow::bail;
use clap::Parser;
use gpuwars::sim::rng::dcmt::{Creator, tempering_parameters};
use indicatif::{ProgressBar, ProgressStyle};
use rayon::prelude::*;

#[derive(Parser)]
#[command(about = "Generate MT607 parameter sets with the Dynamic Creator (dcmt)")]
struct Args {
    /// Seed of the creator (dcmt's `init_dc`).
    #[arg(long)]
    seed: u32,
    /// Number of parameter sets, for ids 0 to count - 1 (at most 65536: ids are 16 bits).
    #[arg(long, value_parser = clap::value_parser!(u32).range(1..=65536))]
    count: u32,
    /// Output file, replaced atomically.
    #[arg(long)]
    out: PathBuf,
}

fn main() -> anyhow::Result<()> {
    let args = Args::parse();
    let progress = ProgressBar::new(u64::from(args.count)).with_style(
        ProgressStyle::with_template("{elapsed_precise} [{bar:40}] {pos}/{len} ids, eta {eta}")?,
    );

    // The sequential search feeds the parallel tempering through a channel.
    let (sender, receiver) = mpsc::channel();
    let (seed, count) = (args.seed, args.count);
    let search = std::thread::spawn(move || -> anyhow::Result<()> {
        let mut creator = Creator::new(seed);
        for id in 0..count {
            let id = id as u16;
            let Some(matrix_a) = creator.matrix_a(id) else {
                bail!("dcmt found no full-period matrix_a for id {id}");
            };
            if sender.send((id, matrix_a)).is_err() {
                break;
            }
        }
        Ok(())
    });
    let mut sets: Vec<_> = receiver
        .into_iter()
        .par_bridge()
        .map(|(id, matrix_a)| {
            let params = tempering_parameters(matrix_a);
            progress.inc(1);
            (id, params)
        })
        .collect();
    search.join().expect("the search thread panicked")?;
    progress.finish();
    sets.sort_unstable_by_key(|&(id, _)| id);

    let mut text = format!(
        "# MT607 parameter sets (w = 32, p = 607) from the Dynamic Creator: dcmt's init_dc({seed})\n\
         # followed by get_mt_parameter_id(32, 607, id) for id = 0..{count} in sequence.\n\
         # Made by: cargo run --release --example mt607_table -- --seed {seed} --count {count} --out FILE\n\
         # Columns: id matrix_a mask_b mask_c\n"
    );
    for (id, p) in &sets {
        writeln!(
            text,
            "{id} {:#010x} {:#010x} {:#010x}",
            p.matrix_a, p.mask_b, p.mask_c
        )?;
    }
    gpuwars::files::write_atomically(&args.out, text.as_bytes())?;
    eprintln!(
        "wrote {} parameter sets to {}",
        sets.len(),
        args.out.display()
    );
    Ok(())
}
