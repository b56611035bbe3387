//! A sharded sweep run as a real Slurm job array on a single-node cluster
//! (`tests/slurm/sweep_array.sh`, which installs Debian's slurm and munge
//! when they are missing): the merged shards equal the unsharded run byte for byte.

use std::path::Path;
use std::process::Command;

#[test]
fn sweep_shards_run_as_a_slurm_job_array_merge_to_the_unsharded_table() {
    let script = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../tests/slurm/sweep_array.sh");
    let output = Command::new("bash")
        .arg(&script)
        .arg(env!("CARGO_BIN_EXE_fistage"))
        .output()
        .expect("bash runs");
    let stdout = String::from_utf8_lossy(&output.stdout);
    let stderr = String::from_utf8_lossy(&output.stderr);
    assert!(output.status.success(), "{stdout}\n{stderr}");
    assert!(
        stdout.contains("merged points.csv equals the unsharded run"),
        "{stdout}\n{stderr}"
    );
}
