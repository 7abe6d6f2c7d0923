//! Compiles `kernels/` to one self-contained PTX module with rustc's nvptx64 backend.
//!
//! A nested `cargo rustc` builds the kernels crate for `nvptx64-nvidia-cuda` as a staticlib
//! with fat LTO (profile `ptx` in Cargo.toml) and `--emit=asm`: LTO pulls `core` and every
//! dependency into the one module, so the PTX has no `.extern` and loads on its own. The result
//! is written to `$OUT_DIR/gpuwars_kernels.ptx` (for inspection) and embedded by `host/ptx.rs`.
//! Baseline `sm_70`: the driver JIT-compiles it for any Volta-or-newer card.

use std::env;
use std::fs;
use std::path::{Path, PathBuf};
use std::process::{Command, exit};

const TARGET: &str = "nvptx64-nvidia-cuda";
const ARCH: &str = "sm_70";

fn main() {
    let root = PathBuf::from(env::var_os("CARGO_MANIFEST_DIR").expect("set by cargo"));
    let out_dir = PathBuf::from(env::var_os("OUT_DIR").expect("set by cargo"));
    let kernels = root.join("kernels");
    println!("cargo::rerun-if-changed={}", kernels.join("src").display());
    println!(
        "cargo::rerun-if-changed={}",
        kernels.join("Cargo.toml").display()
    );
    println!("cargo::rustc-env=GPUWARS_PTX_ARCH={ARCH}");

    let rustc = env::var("RUSTC").unwrap_or_else(|_| "rustc".into());
    check_rust_src(&rustc);

    // Its own target dir: the outer build holds the lock on ours.
    let target_dir = out_dir.join("ptx-target");
    let deps = target_dir.join(TARGET).join("ptx").join("deps");
    let cargo = env::var("CARGO").unwrap_or_else(|_| "cargo".into());
    let mut nested = Command::new(cargo);
    nested
        .current_dir(&root)
        .args(["rustc", "--quiet", "--package", "gpuwars-kernels", "--lib"])
        .args(["--profile", "ptx", "--target", TARGET, "-Zbuild-std=core"])
        .args(["--crate-type", "staticlib", "--target-dir"])
        .arg(&target_dir)
        .args(["--", "--emit=asm", "-C"])
        .arg(format!("target-cpu={ARCH}"))
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
        fail("the nvptx build of kernels/ failed (its messages are above)");
    }

    let asm = newest_asm(&deps)
        .unwrap_or_else(|| fail(&format!("no gpuwars_kernels-*.s in {}", deps.display())));
    let ptx = fs::read_to_string(&asm)
        .unwrap_or_else(|e| fail(&format!("cannot read {}: {e}", asm.display())));
    if let Some(line) = ptx.lines().find(|l| l.trim_start().starts_with(".extern")) {
        fail(&format!(
            "the PTX module is not self-contained: `{}` (a call LTO did not resolve)",
            line.trim()
        ));
    }
    let dest = out_dir.join("gpuwars_kernels.ptx");
    fs::write(&dest, ptx)
        .unwrap_or_else(|e| fail(&format!("cannot write {}: {e}", dest.display())));
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

/// The most recently written `gpuwars_kernels-*.s` (older hashes may linger in `deps`).
fn newest_asm(deps: &Path) -> Option<PathBuf> {
    fs::read_dir(deps)
        .ok()?
        .filter_map(Result::ok)
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
