//! The embedded PTX module: one `.entry` per kernel of the registry, nothing left to link.

use gpuwars::kernels::registry;
use gpuwars::ptx;

#[test]
fn every_kernel_has_an_entry_point() {
    let entries = ptx::entry_points(ptx::PTX);
    for kernel in registry::ALL {
        assert!(
            entries.contains(&kernel.name),
            "no .entry for kernel `{}`",
            kernel.name
        );
    }
    assert_eq!(entries.len(), registry::ALL.len(), "entries: {entries:?}");
}

#[test]
fn module_is_self_contained() {
    // A `.extern` is a call that LTO did not resolve: the driver would refuse the module.
    let externs: Vec<&str> = ptx::PTX.lines().filter(|l| l.contains(".extern")).collect();
    assert!(externs.is_empty(), "{externs:?}");
}

#[test]
fn module_targets_the_baseline_architecture() {
    assert!(
        ptx::PTX
            .lines()
            .any(|l| l.trim() == format!(".target {}", ptx::ARCH))
    );
    assert!(ptx::PTX.lines().any(|l| l.trim() == ".address_size 64"));
}

#[test]
fn build_writes_the_embedded_module_to_out_dir() {
    let on_disk = std::fs::read_to_string(ptx::PTX_PATH).expect("build.rs writes the PTX file");
    assert_eq!(on_disk, ptx::PTX);
}

#[test]
fn kernel_names_are_unique() {
    let mut names: Vec<&str> = registry::ALL.iter().map(|k| k.name).collect();
    names.sort_unstable();
    names.dedup();
    assert_eq!(names.len(), registry::ALL.len());
}
