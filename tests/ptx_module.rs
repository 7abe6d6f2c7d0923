//! The embedded PTX modules: one `.entry` per kernel of the registry, nothing left to link;
//! in the Hopper module, every entry waits for the launch before it before touching memory;
//! the persistent step's entry alone in a module of its own.

use gpuwars::kernels::registry;
use gpuwars::ptx;

/// Both modules, with the architecture each targets.
const MODULES: [(&str, &str); 2] = [
    (ptx::PTX, ptx::ARCH),
    (ptx::DEPENDENT_PTX, ptx::DEPENDENT_ARCH),
];

#[test]
fn every_kernel_has_an_entry_point() {
    for (module, arch) in MODULES {
        let entries = ptx::entry_points(module);
        for kernel in registry::ALL {
            assert!(
                entries.contains(&kernel.name),
                "no .entry for kernel `{}` in the {arch} module",
                kernel.name
            );
        }
        assert_eq!(entries.len(), registry::ALL.len(), "entries: {entries:?}");
    }
}

#[test]
fn module_is_self_contained() {
    // A `.extern` is a call that LTO did not resolve: the driver would refuse the module.
    for (module, arch) in MODULES {
        let externs: Vec<&str> = module.lines().filter(|l| l.contains(".extern")).collect();
        assert!(externs.is_empty(), "{arch}: {externs:?}");
    }
}

#[test]
fn modules_target_their_architectures() {
    for (module, arch) in MODULES {
        assert!(
            module
                .lines()
                .any(|l| l.trim() == format!(".target {arch}"))
        );
        assert!(module.lines().any(|l| l.trim() == ".address_size 64"));
    }
}

/// The body of entry `name` in `module`: from its `.entry` line to the next entry or the end.
fn entry_body<'m>(module: &'m str, name: &str) -> &'m str {
    let head = format!(".entry {name}(");
    let start = module.find(&head).expect("the entry exists");
    let rest = &module[start + head.len()..];
    let end = rest.find(".entry ").unwrap_or(rest.len());
    &rest[..end]
}

/// Whether a PTX instruction line reads or writes memory other than the parameters (or,
/// with `loads` false, writes it or calls).
fn touches_memory(line: &str, loads: bool) -> bool {
    let op = line.trim_start();
    let reads = loads && op.starts_with("ld.") && !op.starts_with("ld.param");
    reads
        || ["st.", "atom.", "red.", "call"]
            .iter()
            .any(|p| op.starts_with(p))
}

#[test]
fn dependent_entries_wait_for_the_launch_before_them_first() {
    // Launched early, a kernel that read or wrote before `griddepcontrol.wait` would race
    // with the launch it follows; those that read the world's own tables first may load
    // there, but not store.
    let mut early = 0;
    for kernel in registry::ALL {
        let body = entry_body(ptx::DEPENDENT_PTX, kernel.name);
        let wait = body
            .find("griddepcontrol.wait;")
            .unwrap_or_else(|| panic!("`{}` never waits", kernel.name));
        let loads = !kernel.reads_before_waiting;
        early += usize::from(kernel.reads_before_waiting);
        let first_access = body
            .lines()
            .find(|l| touches_memory(l, loads))
            .map(|l| body.find(l).expect("a line of the body"));
        assert!(
            first_access.is_none_or(|at| wait < at),
            "`{}` touches memory before it waits",
            kernel.name
        );
    }
    assert!(early > 0 && early < registry::ALL.len());
    assert!(!ptx::PTX.contains("griddepcontrol"));
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

/// The persistent step's module: the cooperative kernels' entries and nothing else (each
/// kernel of the registry is in the other modules), self-contained, for the baseline.
#[test]
fn the_persistent_steps_module_holds_its_entries_only() {
    let names: Vec<&str> = registry::COOPERATIVE.iter().map(|k| k.name).collect();
    assert_eq!(ptx::entry_points(ptx::PROGRAM_PTX), names);
    assert!(!ptx::PROGRAM_PTX.contains(".extern"));
    let target = format!(".target {}", ptx::ARCH);
    assert!(ptx::PROGRAM_PTX.lines().any(|l| l.trim() == target));
    for (module, arch) in MODULES {
        let entries = ptx::entry_points(module);
        assert!(
            names.iter().all(|n| !entries.contains(n)),
            "{arch}: {entries:?}"
        );
    }
}
