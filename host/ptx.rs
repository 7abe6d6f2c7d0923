//! The kernels' PTX modules, built by `build.rs` and embedded in the binary: the baseline
//! for every card, the Hopper one with programmatic dependent launch, and the persistent
//! step's.

/// The PTX text handed to the CUDA driver.
pub const PTX: &str = include_str!(concat!(env!("OUT_DIR"), "/gpuwars_kernels.ptx"));

/// Where `build.rs` wrote the same PTX, for inspection.
pub const PTX_PATH: &str = concat!(env!("OUT_DIR"), "/gpuwars_kernels.ptx");

/// The GPU architecture the PTX targets (the driver JIT-compiles it for newer ones).
pub const ARCH: &str = env!("GPUWARS_PTX_ARCH");

/// The same kernels for [`DEPENDENT_ARCH`] and newer, each entry first waiting for the launch
/// before it (`griddepcontrol`), so that they may be launched before it ends.
pub const DEPENDENT_PTX: &str = include_str!(concat!(env!("OUT_DIR"), "/gpuwars_kernels_sm90.ptx"));

/// The persistent step's module: the cooperative kernels alone (for [`ARCH`]), apart
/// because the driver takes about a minute to compile their one entry, which holds every
/// stage kernel's body: only a persistent step loads it.
pub const PROGRAM_PTX: &str = include_str!(concat!(env!("OUT_DIR"), "/gpuwars_program.ptx"));

/// The GPU architecture [`DEPENDENT_PTX`] targets.
pub const DEPENDENT_ARCH: &str = env!("GPUWARS_PTX_DEPENDENT_ARCH");

/// Names of the `.entry` points declared in a PTX module, in order.
pub fn entry_points(ptx: &str) -> Vec<&str> {
    ptx.lines()
        .filter_map(|line| {
            let rest = line.trim_start();
            let rest = rest.strip_prefix(".visible ").unwrap_or(rest);
            let name = rest.strip_prefix(".entry")?.trim_start();
            let end = name
                .find(|c: char| !(c.is_ascii_alphanumeric() || c == '_' || c == '$'))
                .unwrap_or(name.len());
            (end > 0).then(|| &name[..end])
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::entry_points;

    #[test]
    fn finds_entries_with_and_without_visibility() {
        let ptx =
            ".version 6.0\n.visible .entry foo(\n\t.param .u64 p\n)\n.entry bar_2 (\n.func baz(\n";
        assert_eq!(entry_points(ptx), ["foo", "bar_2"]);
    }
}
