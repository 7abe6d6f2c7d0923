//! The `gpuwars` command as a user runs it.

use std::process::Command;

use gpuwars::kernels::registry;
use serde_json::Value;

fn gpuwars(args: &[&str]) -> std::process::Output {
    Command::new(env!("CARGO_BIN_EXE_gpuwars"))
        .args(args)
        .env_remove("GPUWARS_BACKEND")
        .env_remove("GPUWARS_CPU_THREADS")
        .output()
        .expect("the binary runs")
}

fn gpu_present() -> bool {
    gpuwars::Device::cuda("probe").is_ok()
}

fn info_json(args: &[&str]) -> Value {
    let out = gpuwars(args);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    serde_json::from_slice(&out.stdout).expect("info --json prints JSON")
}

#[test]
fn info_json_on_the_cpu_names_the_backend_the_reason_and_every_kernel() {
    let info = info_json(&["info", "--json", "--backend", "cpu", "--cpu-threads", "3"]);
    assert_eq!(info["backend"], "cpu");
    assert!(
        info["backend_reason"]
            .as_str()
            .unwrap()
            .contains("--backend cpu")
    );
    assert_eq!(info["cpu_threads"], 3);
    assert_eq!(info["version"], env!("CARGO_PKG_VERSION"));
    let mut entries: Vec<&str> = info["ptx"]["entry_points"]
        .as_array()
        .unwrap()
        .iter()
        .map(|v| v.as_str().unwrap())
        .collect();
    let mut kernels: Vec<&str> = registry::ALL.iter().map(|k| k.name).collect();
    entries.sort_unstable();
    kernels.sort_unstable();
    assert_eq!(entries, kernels);
    assert_eq!(info["ptx"]["missing_kernels"], Value::Array(vec![]));
    assert!(info["ptx"]["bytes"].as_u64().unwrap() > 1000);
}

#[test]
fn auto_picks_the_gpu_when_there_is_one_and_says_why_when_not() {
    let out = gpuwars(&["info", "--json"]);
    assert!(out.status.success());
    let info: Value = serde_json::from_slice(&out.stdout).unwrap();
    let stderr = String::from_utf8_lossy(&out.stderr);
    if gpu_present() {
        assert_eq!(info["backend"], "cuda");
        assert!(info["device"]["name"].as_str().is_some());
    } else {
        assert_eq!(info["backend"], "cpu");
        let reason = info["backend_reason"].as_str().unwrap();
        assert!(!reason.is_empty());
        // Said once, on stderr.
        assert_eq!(
            stderr
                .matches("running the kernels on the CPU emulation")
                .count(),
            1,
            "{stderr}"
        );
        assert!(stderr.contains(reason), "{stderr}");
    }
}

#[test]
fn the_environment_variable_selects_the_backend() {
    let out = Command::new(env!("CARGO_BIN_EXE_gpuwars"))
        .args(["info", "--json"])
        .env("GPUWARS_BACKEND", "cpu")
        .output()
        .unwrap();
    let info: Value = serde_json::from_slice(&out.stdout).unwrap();
    assert_eq!(info["backend"], "cpu");
}

#[test]
fn asking_for_cuda_without_a_gpu_is_a_clear_error() {
    if gpu_present() {
        eprintln!("skipped: a GPU is present");
        return;
    }
    let out = gpuwars(&["info", "--backend", "cuda"]);
    assert_eq!(out.status.code(), Some(1));
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(
        stderr.contains("the CUDA backend is not available"),
        "{stderr}"
    );
    assert!(!stderr.contains("panicked"), "{stderr}");
}

#[test]
fn bad_flags_name_the_allowed_values() {
    let out = gpuwars(&["info", "--backend", "gpu"]);
    assert_eq!(out.status.code(), Some(2));
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(
        stderr.contains("possible values: auto, cuda, cpu"),
        "{stderr}"
    );
    let out = gpuwars(&["info", "--cpu-threads", "0"]);
    assert_eq!(out.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&out.stderr).contains("1..=1024"));
}

#[test]
fn text_info_is_the_default_command() {
    let out = gpuwars(&["--backend", "cpu"]);
    assert!(out.status.success());
    let stdout = String::from_utf8_lossy(&out.stdout);
    assert!(
        stdout.starts_with(&format!("gpuwars {}", env!("CARGO_PKG_VERSION"))),
        "{stdout}"
    );
    assert!(stdout.contains("backend:      cpu"), "{stdout}");
}
