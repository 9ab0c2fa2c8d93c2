//! `render --mpi` under a real MPI launcher (built with `--features mpi`; CI installs
//! OpenMPI): the image equals the single-process image, bit for bit, for ray casting and
//! path tracing, one worker or two, single frames and walkthroughs; a bad command line is
//! one message for the whole job.

use std::path::Path;
use std::process::{Command, Output};

use crate::common::*;

fn mpirun(dir: &Path, ranks: u32, args: &[&str]) -> Output {
    mpirun_command(dir, ranks, args).output().expect("mpirun runs (install OpenMPI: openmpi-bin)")
}

fn mpirun_command(dir: &Path, ranks: u32, args: &[&str]) -> Command {
    let mut c = Command::new("mpirun");
    // More ranks than cores is fine here: the tests check images, not speed.
    c.args(["-n", &ranks.to_string(), "--oversubscribe"]);
    c.arg(env!("CARGO_BIN_EXE_raypipe"))
        .args(args)
        .current_dir(dir)
        // OpenMPI refuses root unless told (CI's containers run as root).
        .env("OMPI_ALLOW_RUN_AS_ROOT", "1")
        .env("OMPI_ALLOW_RUN_AS_ROOT_CONFIRM", "1")
        // Containers often forbid the cross-process memory copy OpenMPI tries first.
        .env("OMPI_MCA_btl_vader_single_copy_mechanism", "none");
    c
}

/// The pid of rank `rank` among the children of `launcher` (OpenMPI starts the ranks
/// of its own host as its children, and names the rank in their environment).
fn rank_pid(launcher: u32, rank: u32) -> Option<u32> {
    let want = format!("OMPI_COMM_WORLD_RANK={rank}");
    std::fs::read_dir("/proc").ok()?.flatten().find_map(|e| {
        let pid: u32 = e.file_name().to_str()?.parse().ok()?;
        let stat = std::fs::read_to_string(format!("/proc/{pid}/stat")).ok()?;
        let ppid: u32 = stat.rsplit_once(')')?.1.split_whitespace().nth(1)?.parse().ok()?;
        let env = std::fs::read(format!("/proc/{pid}/environ")).ok()?;
        (ppid == launcher && env.split(|&b| b == 0).any(|v| v == want.as_bytes())).then_some(pid)
    })
}

/// A long path-traced render on three ranks whose rank 1 gets `signal` once the
/// workers are rendering; what the job printed, and how it ended.
fn render_and_signal(dir: &Path, signal: &str) -> Output {
    use std::io::BufRead;
    let args = ["render", "--mpi", "--algo", "path", "--samples", "64", "--size", "256x256", "--mpi-timeout", "2"];
    let mut child = mpirun_command(dir, 3, &[&args[..], &["-o", "a.png"]].concat())
        .stdout(std::process::Stdio::piped())
        .stderr(std::process::Stdio::piped())
        .spawn()
        .expect("mpirun runs (install OpenMPI: openmpi-bin)");
    // The master's first line comes once every worker has loaded the scene.
    let mut stdout = std::io::BufReader::new(child.stdout.take().unwrap());
    let mut first = String::new();
    stdout.read_line(&mut first).unwrap();
    assert!(first.starts_with("mpi"), "{first}");
    std::thread::sleep(std::time::Duration::from_millis(300));
    let pid = rank_pid(child.id(), 1).expect("rank 1 runs under mpirun");
    let killed = Command::new("kill").args([signal, &pid.to_string()]).status().unwrap();
    assert!(killed.success());
    let mut rest = Vec::new();
    std::io::Read::read_to_end(&mut stdout, &mut rest).unwrap();
    let mut o = child.wait_with_output().unwrap();
    o.stdout = [first.into_bytes(), rest].concat();
    // A stopped rank is left for the launcher to end; make sure it is gone.
    let _ = Command::new("kill").args(["-KILL", &pid.to_string()]).stderr(std::process::Stdio::null()).status();
    o
}

#[test]
fn mpi_frames_equal_single_process_frames() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    for (algo, samples) in [("cast", "1"), ("whitted", "1"), ("path", "4")] {
        let common = ["render", "--size", "96x72", "--algo", algo, "--samples", samples];
        let o = raypipe(d, &[&common[..], &["-o", "one.png"]].concat());
        assert!(o.status.success(), "{}", stderr(&o));
        for ranks in [2, 3] {
            let o = mpirun(d, ranks, &[&common[..], &["-o", "mpi.png", "--mpi", "--mpi-tile", "24"]].concat());
            assert!(o.status.success(), "{algo} on {ranks} ranks: {}", stderr(&o));
            let out = String::from_utf8_lossy(&o.stdout);
            assert!(out.contains("mpi share") && out.contains("rank 1"), "{out}");
            assert_eq!(decode(&d.join("one.png")), decode(&d.join("mpi.png")), "{algo} on {ranks} ranks");
        }
    }
    // A walkthrough: every frame equal; from the second frame on tiles stay with their
    // worker.
    let o = raypipe(d, &["render", "--size", "64x48", "--orbit", "3", "-o", "w.png"]);
    assert!(o.status.success(), "{}", stderr(&o));
    let o = mpirun(d, 3, &["render", "--size", "64x48", "--orbit", "3", "-o", "m.png", "--mpi", "--mpi-tile", "16"]);
    assert!(o.status.success(), "{}", stderr(&o));
    let out = String::from_utf8_lossy(&o.stdout);
    assert!(out.contains("kept tiles") && out.contains("frames/s"), "{out}");
    for k in 0..3 {
        let name = |s: &str| d.join(format!("{s}-{k:04}.png"));
        assert_eq!(decode(&name("w")), decode(&name("m")), "frame {k}");
    }
}

#[test]
fn bricked_frames_equal_single_process_frames_replicated_and_served() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let o = raypipe(
        d,
        &["build", "--generate", "powerplant:triangles=20000", "--bricks", "--brick-size", "16K", "-o", "p.rpsb"],
    );
    assert!(o.status.success(), "{}", stderr(&o));
    // A cache smaller than the scene: bricks are evicted and fetched again.
    for algo in ["cast", "whitted"] {
        let common = ["render", "p.rpsb", "--size", "80x60", "--algo", algo, "--cache", "512K"];
        let o = raypipe(d, &[&common[..], &["-o", "one.png"]].concat());
        assert!(o.status.success(), "{}", stderr(&o));
        for (data, ranks) in [("replicated", 2), ("served", 2), ("served", 3)] {
            let mpi = ["-o", "mpi.png", "--mpi", "--mpi-tile", "16", "--mpi-data", data];
            let o = mpirun(d, ranks, &[&common[..], &mpi[..]].concat());
            assert!(o.status.success(), "{algo}, {data} on {ranks} ranks: {}", stderr(&o));
            let out = String::from_utf8_lossy(&o.stdout);
            let how = if data == "served" { "MB served" } else { "MB read" };
            assert!(out.contains("hit rate") && out.contains(how), "{out}");
            assert_eq!(decode(&d.join("one.png")), decode(&d.join("mpi.png")), "{algo}, {data} on {ranks} ranks");
        }
    }
    // A served walkthrough: every frame equal, the caches' hit rates per worker; its
    // recording replays on the cluster model.
    let walk = ["render", "p.rpsb", "--size", "48x32", "--orbit", "3", "--cache", "512K"];
    let o = raypipe(d, &[&walk[..], &["-o", "w.png"]].concat());
    assert!(o.status.success(), "{}", stderr(&o));
    let mpi = ["-o", "m.png", "--mpi", "--mpi-data", "served", "--mpi-record", "rec.jsonl"];
    let o = mpirun(d, 3, &[&walk[..], &mpi[..]].concat());
    assert!(o.status.success(), "{}", stderr(&o));
    assert!(String::from_utf8_lossy(&o.stdout).contains("hit rate per worker"));
    let o = raypipe(d, &["cluster", "rec.jsonl", "--served", "--workers", "1,2,64", "--check", "rec.jsonl"]);
    assert!(o.status.success(), "{}", stderr(&o));
    let out = String::from_utf8_lossy(&o.stdout);
    assert!(out.contains("3 frames of 48x32") && out.contains("check    2 workers on 1 host"), "{out}");
    for k in 0..3 {
        let name = |s: &str| d.join(format!("{s}-{k:04}.png"));
        assert_eq!(decode(&name("w")), decode(&name("m")), "frame {k}");
    }
    // Served data need a bricked scene: one line for the whole job.
    let o = mpirun(d, 3, &["render", "--mpi", "--mpi-data", "served", "-o", "x.png"]);
    assert!(!o.status.success());
    let err = stderr(&o);
    let errors: Vec<&str> = err.lines().filter(|l| l.starts_with("error:")).collect();
    assert!(errors.len() == 1 && errors[0].contains("needs a bricked scene"), "{err}");
}

#[test]
fn a_bad_mpi_command_line_is_one_message() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    for args in [&["render", "--mpi", "--no-such-flag"][..], &["render", "missing.obj", "--mpi"][..]] {
        let o = mpirun(d, 3, args);
        assert!(!o.status.success());
        let errors = stderr(&o).lines().filter(|l| l.starts_with("error:")).count();
        assert_eq!(errors, 1, "{args:?}: {}", stderr(&o));
    }
    assert!(only_files(d).is_empty());
    // One rank is no job: a master needs a worker.
    let o = mpirun(d, 1, &["render", "--mpi", "-o", "x.png"]);
    assert!(stderr(&o).contains("needs a master and at least one worker"), "{}", stderr(&o));
}

#[test]
fn a_dead_or_hung_worker_ends_the_job_with_one_line_naming_it_and_its_tile() {
    for signal in ["-KILL", "-STOP"] {
        let dir = tempfile::tempdir().unwrap();
        let o = render_and_signal(dir.path(), signal);
        assert!(!o.status.success(), "{signal}: {}", stderr(&o));
        let errors: Vec<String> = stderr(&o).lines().filter(|l| l.starts_with("error:")).map(String::from).collect();
        assert_eq!(errors.len(), 1, "{signal}: {}", stderr(&o));
        assert!(errors[0].contains("rank 1") && errors[0].contains("tile"), "{signal}: {}", errors[0]);
        // No image, not even part of one.
        assert!(only_files(dir.path()).is_empty(), "{signal}: {:?}", only_files(dir.path()));
    }
}

#[test]
fn mpi_sweeps_write_the_single_process_rows() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let tetra = fixtures().join("tetra.obj");
    write(
        d,
        "spec.toml",
        &format!(
            "[fixed]\nscene = {:?}\nsize = \"24x16\"\n[grid]\n\"traversal.units\" = [1, 2]\npacket_size = [4, 16]\n\
             [[points]]\naccel = \"kd\"\n[[points]]\naccel = \"bvh4\"\n\"memory.model\" = \"dram\"\n",
            tetra.display().to_string()
        ),
    );
    let o = raypipe(d, &["sweep", "spec.toml", "-o", "one"]);
    assert!(o.status.success(), "{}", stderr(&o));
    for ranks in [2, 3] {
        let o = mpirun(d, ranks, &["sweep", "spec.toml", "-o", "mpi", "--mpi", "--restart"]);
        assert!(o.status.success(), "{ranks} ranks: {}", stderr(&o));
        for ext in ["jsonl", "csv"] {
            let read = |s: &str| std::fs::read(d.join(format!("{s}.{ext}"))).unwrap();
            assert!(read("one") == read("mpi"), "{ranks} ranks: {ext} differs");
        }
    }
    // Resumed with nothing left to run: the workers are let go.
    let o = mpirun(d, 3, &["sweep", "spec.toml", "-o", "mpi", "--mpi"]);
    assert!(o.status.success(), "{}", stderr(&o));
    assert!(String::from_utf8_lossy(&o.stdout).contains("0 to run"));
}
