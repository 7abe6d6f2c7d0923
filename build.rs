//! Compiles `kernels/` to self-contained PTX modules with rustc's nvptx64 backend.
//!
//! A nested `cargo rustc` builds the kernels crate for `nvptx64-nvidia-cuda` as a staticlib
//! with fat LTO (profile `ptx` in Cargo.toml) and `--emit=asm`: LTO pulls `core` and every
//! dependency into the one module, so the PTX has no `.extern` and loads on its own. The result
//! is written to `$OUT_DIR/gpuwars_kernels.ptx` (for inspection) and embedded by `host/ptx.rs`.
//! Baseline `sm_70`: the driver JIT-compiles it for any Volta-or-newer card. A second module,
//! `gpuwars_kernels_sm90.ptx`, is built from the same source for Hopper with programmatic
//! dependent launch (every entry first waits for the launch before it).
//!
//! It also turns the committed table of MT607 parameter sets (`data/mt607_params.txt`, made by
//! `examples/mt607_table.rs`) into a Rust array, `$OUT_DIR/mt607_params.rs`, so that a damaged
//! table stops the build with its line number instead of failing at run time.

use std::env;
use std::fs;
use std::path::{Path, PathBuf};
use std::process::{Command, exit};

const TARGET: &str = "nvptx64-nvidia-cuda";

/// One PTX module built from `kernels/`.
struct Module {
    /// The file written to `$OUT_DIR`.
    file: &'static str,
    /// The GPU architecture it targets (`-C target-cpu`).
    arch: &'static str,
    /// Its nested build's own target directory, under `$OUT_DIR` (`ptx-target-DIR`).
    dir: &'static str,
    /// Further `rustc` arguments: the PTX version and the cfg of what only it has.
    flags: &'static [&'static str],
    /// Whether its entries of [`REGISTER_CAPS`] are capped (the modules of every kernel).
    capped: bool,
}

/// The baseline module, JIT-compiled by the driver for any Volta-or-newer card; the Hopper
/// module, whose kernels wait for the launch before them so that the host can launch them
/// early (programmatic dependent launch needs sm_90 and PTX 7.8); and the persistent step's
/// module, whose one entry holds every stage kernel's body (the driver takes about a minute
/// to compile it, so it is loaded only when a persistent step is made).
const MODULES: [Module; 3] = [
    Module {
        file: "gpuwars_kernels.ptx",
        arch: "sm_70",
        dir: "sm_70",
        flags: &[],
        capped: true,
    },
    Module {
        file: "gpuwars_program.ptx",
        arch: "sm_70",
        dir: "program",
        flags: &["--cfg", "gpuwars_program"],
        capped: false,
    },
    Module {
        file: "gpuwars_kernels_sm90.ptx",
        arch: "sm_90",
        dir: "sm_90",
        flags: &[
            "-C",
            "target-feature=+ptx78",
            "--cfg",
            "gpuwars_dependent_launch",
        ],
        capped: true,
    },
];

fn main() {
    let root = PathBuf::from(env::var_os("CARGO_MANIFEST_DIR").expect("set by cargo"));
    let out_dir = PathBuf::from(env::var_os("OUT_DIR").expect("set by cargo"));
    let kernels = root.join("kernels");
    println!("cargo::rerun-if-changed={}", kernels.join("src").display());
    println!(
        "cargo::rerun-if-changed={}",
        kernels.join("Cargo.toml").display()
    );
    println!("cargo::rustc-env=GPUWARS_PTX_ARCH={}", MODULES[0].arch);
    println!(
        "cargo::rustc-env=GPUWARS_PTX_DEPENDENT_ARCH={}",
        MODULES[2].arch
    );
    embed_commit(&root);
    embed_rng_table(&root.join("data").join("mt607_params.txt"), &out_dir);

    let rustc = env::var("RUSTC").unwrap_or_else(|_| "rustc".into());
    check_rust_src(&rustc);
    let allow_cpu_mismatch = knows_target_cpu_as_modifier(&rustc, &out_dir);
    for module in &MODULES {
        let ptx = build_ptx(&root, &out_dir, module, allow_cpu_mismatch);
        let ptx = if module.capped {
            cap_registers(ptx)
        } else {
            ptx
        };
        let dest = out_dir.join(module.file);
        fs::write(&dest, ptx)
            .unwrap_or_else(|e| fail(&format!("cannot write {}: {e}", dest.display())));
    }
}

/// Whether `rustc` takes `-C target-cpu` as a target modifier, which every crate of a build
/// must share (nightlies since late 2026; stable 1.95 does not, and refuses the flag that
/// allows a mismatch): probed by compiling an empty crate with that flag.
fn knows_target_cpu_as_modifier(rustc: &str, out_dir: &Path) -> bool {
    Command::new(rustc)
        .args([
            ABI_MISMATCH_ALLOWED,
            "--crate-type",
            "lib",
            "--crate-name",
            "probe",
        ])
        .args(["--emit", "metadata", "-o"])
        .arg(out_dir.join("probe.rmeta"))
        .arg("-")
        .stdin(std::process::Stdio::null())
        .stderr(std::process::Stdio::null())
        .status()
        .is_ok_and(|status| status.success())
}

/// Lets the kernels' crate take a `target-cpu` that `core` and the other dependencies, built
/// without one, do not share. Sound here: fat LTO compiles them into the kernels' one module
/// for its `target-cpu`, exactly what a stable rustc does without being asked.
const ABI_MISMATCH_ALLOWED: &str = "-Cunsafe-allow-abi-mismatch=target-cpu";

/// The PTX text of `module`, built by a nested cargo (allowing the kernels' `target-cpu`
/// apart from their dependencies' where `rustc` would refuse it, `allow_cpu_mismatch`).
fn build_ptx(root: &Path, out_dir: &Path, module: &Module, allow_cpu_mismatch: bool) -> String {
    // Its own target dir: the outer build holds the lock on ours; one per module, so that
    // each keeps its incremental state.
    let target_dir = out_dir.join(format!("ptx-target-{}", module.dir));
    let profile_dir = target_dir.join(TARGET).join("ptx");
    let cargo = env::var("CARGO").unwrap_or_else(|_| "cargo".into());
    let mut nested = Command::new(cargo);
    nested
        .current_dir(root)
        .args(["rustc", "--quiet", "--package", "gpuwars-kernels", "--lib"])
        .args(["--profile", "ptx", "--target", TARGET, "-Zbuild-std=core"])
        .args(["--crate-type", "staticlib", "--target-dir"])
        .arg(&target_dir)
        .args(["--", "--emit=asm", "-C"])
        .arg(format!("target-cpu={}", module.arch))
        .args(module.flags)
        .args(allow_cpu_mismatch.then_some(ABI_MISMATCH_ALLOWED))
        // -Zbuild-std is unstable; this is the documented way to use it on a stable toolchain.
        .env("RUSTC_BOOTSTRAP", "1");
    // What the outer build passes to its own rustc must not leak into the nvptx build.
    for var in [
        "RUSTFLAGS",
        "CARGO_ENCODED_RUSTFLAGS",
        "CARGO_BUILD_RUSTFLAGS",
        "RUSTC_WRAPPER",
        "RUSTC_WORKSPACE_WRAPPER",
        "CARGO_BUILD_TARGET",
        "CARGO_TARGET_DIR",
        "CARGO_BUILD_TARGET_DIR",
    ] {
        nested.env_remove(var);
    }
    let output = nested
        .output()
        .unwrap_or_else(|e| fail(&format!("cannot run cargo: {e}")));
    if !output.status.success() {
        eprintln!("{}", String::from_utf8_lossy(&output.stderr));
        fail(&format!(
            "the nvptx build of kernels/ for {} failed (its messages are above)",
            module.arch
        ));
    }

    let asm = newest_asm(&profile_dir).unwrap_or_else(|| {
        fail(&format!(
            "no gpuwars_kernels-*.s under {}",
            profile_dir.display()
        ))
    });
    let ptx = fs::read_to_string(&asm)
        .unwrap_or_else(|e| fail(&format!("cannot read {}: {e}", asm.display())));
    if let Some(line) = ptx.lines().find(|l| l.trim_start().starts_with(".extern")) {
        fail(&format!(
            "the PTX module is not self-contained: `{}` (a call LTO did not resolve)",
            line.trim()
        ));
    }
    ptx
}

/// Register caps (`.maxnreg`, what CUDA C's launch bounds give) for the entries whose speed
/// their occupancy decides. `think_in_teams` needs 92 registers on sm_90: 5 blocks of 128
/// threads a multiprocessor, which put `paper`'s 736 blocks in 1.12 waves; at 80 a
/// multiprocessor holds 6 (one wave) for 8 bytes of spills. The one-thread `think`, whose
/// gathers wait on memory at millions of bodies, hides more of that wait with more warps:
/// 80 → 56 registers (6 → 9 blocks a multiprocessor) took it from 197 to 168 µs a step at
/// 1M enemies and from 2.60 to 2.12 ms at 16.76M on an H100 (64 gave 170 and 2.18), the
/// same at 8K. `collide_think_integrate` runs `think_in_teams`'s machines, capped alike, and
/// so does its swept twin, which uncapped took 160 registers (one block a multiprocessor:
/// `paper`'s step 68 µs instead of 62 on an H200). The swept narrow phases took 96 and 142
/// registers against their plain twins' 76 and 84. At a million enemies almost every body's
/// narrow phase finds nothing around and only streams its own state, which more warps do
/// faster: `collide_circles_swept` at 64 rather than 80 took `narrow` from 32.5 to 29.2 µs
/// a step on an H200 (56 was slower than 64 on an H100). The logged twins (audit runs)
/// keep their twins' caps, so that an audited run's blocks fill the GPU as the game's do.
const REGISTER_CAPS: &[(&str, u32)] = &[
    ("think_in_teams", 80),
    ("collide_think_integrate", 80),
    ("collide_think_integrate_swept", 80),
    ("collide_think_integrate_logged", 80),
    ("collide_think_integrate_swept_logged", 80),
    ("collide_circles_swept", 64),
    ("collide_circles_swept_logged", 64),
    ("collide_swept", 96),
    ("collide_swept_logged", 96),
    ("think", 56),
];

/// `ptx` with the [`REGISTER_CAPS`] written after their entries' parameter lists.
fn cap_registers(mut ptx: String) -> String {
    for (entry, cap) in REGISTER_CAPS {
        let head = format!(".entry {entry}(");
        let Some(at) = ptx.find(&head) else {
            fail(&format!(
                "no entry {entry} in the PTX module to cap the registers of"
            ));
        };
        let close = at + ptx[at..].find(')').expect("an entry's parameter list ends");
        ptx.insert_str(close + 1, &format!("\n.maxnreg {cap}"));
    }
    ptx
}

/// `-Zbuild-std` compiles `core` from the `rust-src` component; without it the nested build
/// fails with pages of noise, so say what is missing in one line.
fn check_rust_src(rustc: &str) {
    let sysroot = Command::new(rustc)
        .args(["--print", "sysroot"])
        .output()
        .ok()
        .filter(|o| o.status.success())
        .map(|o| PathBuf::from(String::from_utf8_lossy(&o.stdout).trim()));
    let Some(sysroot) = sysroot else {
        fail(&format!("cannot ask `{rustc} --print sysroot`"));
    };
    let core = sysroot.join("lib/rustlib/src/rust/library/core/Cargo.toml");
    if !core.is_file() {
        fail(
            "the rust-src component is missing (needed to build the GPU kernels); \
             install it with: rustup component add rust-src",
        );
    }
}

/// The most recently written `gpuwars_kernels-*.s` of the nested build's profile folder
/// (older hashes may linger): in `deps`, where a stable cargo writes it, or in
/// `build/gpuwars-kernels/*/out`, where a nightly cargo's per-unit build folders put it (the
/// nightly that `scripts/miri` runs).
fn newest_asm(profile_dir: &Path) -> Option<PathBuf> {
    let files_in = |dir: PathBuf| {
        fs::read_dir(dir)
            .into_iter()
            .flatten()
            .filter_map(Result::ok)
    };
    let units = files_in(profile_dir.join("build").join("gpuwars-kernels"))
        .map(|unit| unit.path().join("out"));
    std::iter::once(profile_dir.join("deps"))
        .chain(units)
        .flat_map(files_in)
        .filter(|e| {
            let name = e.file_name();
            let name = name.to_string_lossy();
            name.starts_with("gpuwars_kernels-") && name.ends_with(".s")
        })
        .max_by_key(|e| e.metadata().and_then(|m| m.modified()).ok())
        .map(|e| e.path())
}

fn fail(message: &str) -> ! {
    println!("cargo::error={message}");
    exit(1)
}

/// Writes `$OUT_DIR/mt607_params.rs`: the table's `(matrix_a, mask_b, mask_c)` rows as an array
/// expression. Rows are `id matrix_a mask_b mask_c` (hex with `0x`), ids 0, 1, 2, … in order;
/// lines starting with `#` are comments.
fn embed_rng_table(table: &Path, out_dir: &Path) {
    println!("cargo::rerun-if-changed={}", table.display());
    let text = fs::read_to_string(table).unwrap_or_else(|e| {
        println!("cargo::error=cannot read {}: {e}", table.display());
        exit(1)
    });
    let mut rows = String::from("[\n");
    let mut next_id = 0u32;
    for (number, line) in text.lines().enumerate() {
        if line.starts_with('#') || line.trim().is_empty() {
            continue;
        }
        let fields: Vec<&str> = line.split_whitespace().collect();
        let parsed = match fields.as_slice() {
            [id, a, b, c] => id.parse::<u32>().ok().zip(
                [a, b, c]
                    .iter()
                    .map(|f| {
                        f.strip_prefix("0x")
                            .and_then(|h| u32::from_str_radix(h, 16).ok())
                    })
                    .collect::<Option<Vec<u32>>>(),
            ),
            _ => None,
        };
        match parsed {
            Some((id, words)) if id == next_id => {
                rows += &format!(
                    "    [{:#010x}, {:#010x}, {:#010x}],\n",
                    words[0], words[1], words[2]
                );
                next_id += 1;
            }
            _ => {
                println!(
                    "cargo::error={}:{}: expected `{next_id} 0x<matrix_a> 0x<mask_b> 0x<mask_c>`, found `{line}`",
                    table.display(),
                    number + 1
                );
                exit(1)
            }
        }
    }
    rows += "]\n";
    fs::write(out_dir.join("mt607_params.rs"), rows).expect("OUT_DIR is writable");
}

/// The commit being built, for the benchmarks' reports (`GPUWARS_COMMIT`; "unknown" outside
/// a git checkout).
fn embed_commit(root: &Path) {
    let git = |args: &[&str]| {
        Command::new("git")
            .args(args)
            .current_dir(root)
            .output()
            .ok()
            .filter(|o| o.status.success())
            .map(|o| String::from_utf8_lossy(&o.stdout).trim().to_string())
    };
    let commit = git(&["rev-parse", "HEAD"]).unwrap_or_else(|| "unknown".into());
    if let Some(dir) = git(&["rev-parse", "--absolute-git-dir"]) {
        let dir = PathBuf::from(dir);
        println!("cargo::rerun-if-changed={}", dir.join("HEAD").display());
        // The branch's ref, or the packed refs it lives in (a missing file would rerun
        // this script on every build).
        let branch = git(&["symbolic-ref", "-q", "HEAD"]).map(|head| dir.join(head));
        let packed = dir.join("packed-refs");
        for file in branch.iter().chain([&packed]) {
            if file.exists() {
                println!("cargo::rerun-if-changed={}", file.display());
            }
        }
    }
    println!("cargo::rustc-env=GPUWARS_COMMIT={commit}");
}
