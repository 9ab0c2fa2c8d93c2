//! What outputs write over: a FIFO or device is written through, never replaced; a
//! socket or folder is refused; a command's outputs appear all together or not at all;
//! a killed run's temporary files are cleared by the next write.

use std::io::Read;
use std::os::unix::fs::FileTypeExt;
use std::path::Path;

use super::common::*;

fn mkfifo(path: &Path) {
    let c = std::ffi::CString::new(path.as_os_str().as_encoded_bytes()).unwrap();
    // SAFETY: a valid NUL-terminated path.
    assert_eq!(unsafe { libc::mkfifo(c.as_ptr(), 0o600) }, 0, "mkfifo");
}

/// Reads everything written to the FIFO at `path` on a thread (it blocks until a
/// writer opens it; if the FIFO is replaced instead, the thread stays blocked and is
/// left behind).
fn drain(path: &Path) -> std::sync::mpsc::Receiver<Vec<u8>> {
    let (tx, rx) = std::sync::mpsc::channel();
    let path = path.to_path_buf();
    std::thread::spawn(move || {
        let mut bytes = Vec::new();
        std::fs::File::open(&path).unwrap().read_to_end(&mut bytes).unwrap();
        let _ = tx.send(bytes);
    });
    rx
}

#[test]
fn a_fifo_is_written_through_not_replaced() {
    let dir = tempfile::tempdir().unwrap();
    let fixtures = fixtures();
    for (args, out) in [
        (vec!["build", "tetra.obj", "-o"], "image.fifo"),
        (vec!["simulate", "--size", "16x16", "-o", "a.png", "--report"], "report.fifo"),
        (vec!["rays", "--size", "4x4", "-o"], "rays.fifo"),
    ] {
        let fifo = dir.path().join(out);
        mkfifo(&fifo);
        let got = drain(&fifo);
        let mut args: Vec<String> = args.iter().map(|s| s.to_string()).collect();
        if args[0] == "build" {
            args[1] = fixtures.join("tetra.obj").display().to_string();
        }
        args.push(fifo.display().to_string());
        let refs: Vec<&str> = args.iter().map(String::as_str).collect();
        let o = raypipe(dir.path(), &refs);
        assert!(o.status.success(), "{args:?}: {}", stderr(&o));
        let kind = std::fs::symlink_metadata(&fifo).unwrap().file_type();
        assert!(kind.is_fifo(), "{args:?} replaced the FIFO with {kind:?}");
        let bytes = got.recv_timeout(std::time::Duration::from_secs(30)).expect("the reader got the output");
        assert!(!bytes.is_empty(), "{args:?}: nothing reached the FIFO's reader");
    }
    assert!(only_files(dir.path()).iter().all(|f| !f.starts_with('.')), "{:?}", only_files(dir.path()));
}

#[test]
fn dev_null_takes_an_output() {
    let dir = tempfile::tempdir().unwrap();
    let o = raypipe(dir.path(), &["simulate", "--size", "16x16", "-o", "a.png", "--report", "/dev/null"]);
    assert!(o.status.success(), "{}", stderr(&o));
    let kind = std::fs::metadata("/dev/null").unwrap().file_type();
    assert!(kind.is_char_device(), "/dev/null is now {kind:?}");
    assert_eq!(only_files(dir.path()), ["a.png"]);
}

#[test]
fn a_socket_or_folder_is_refused_before_anything_is_written() {
    let dir = tempfile::tempdir().unwrap();
    let sock = dir.path().join("s");
    let _listener = std::os::unix::net::UnixListener::bind(&sock).unwrap();
    let o = raypipe(dir.path(), &["simulate", "--size", "16x16", "-o", "a.png", "--report", "s"]);
    assert_one_line_error(&o, "s: is a socket");
    std::fs::create_dir(dir.path().join("d")).unwrap();
    let o = raypipe(dir.path(), &["simulate", "--size", "16x16", "-o", "a.png", "--report", "d"]);
    assert_one_line_error(&o, "d: is a directory");
    assert_eq!(only_files(dir.path()), ["d", "s"]);
}

#[test]
fn a_failed_second_output_leaves_no_first() {
    let dir = tempfile::tempdir().unwrap();
    // The triangles' folder disappears only after the rays could be written: a
    // read-only folder refuses the file, whoever runs the test (root included).
    let o = raypipe(dir.path(), &["rays", "--size", "4x4", "-o", "rt.npy", "--triangles", "gone/t.npy"]);
    assert_one_line_error(&o, "gone/t.npy");
    assert_eq!(only_files(dir.path()), Vec::<String>::new());
}

#[test]
fn a_killed_runs_temporaries_are_cleared_by_the_next_write() {
    let dir = tempfile::tempdir().unwrap();
    // A leftover of a process of this machine that no longer runs (pid beyond
    // pid_max), one of this live process and one of another machine (a shared file
    // system): only the first goes.
    let host = std::fs::read_to_string("/proc/sys/kernel/hostname").unwrap().trim().replace(['-', '/', '@'], "_");
    write(dir.path(), &format!(".rays.npy.raypipe-4194305@{host}-abcdef"), "partial");
    let live = format!(".rays.npy.raypipe-{}@{host}-abcdef", std::process::id());
    write(dir.path(), &live, "partial");
    let remote = ".rays.npy.raypipe-4194305@elsewhere-abcdef".to_string();
    write(dir.path(), &remote, "partial");
    let o = raypipe(dir.path(), &["rays", "--size", "4x4", "-o", "rays.npy"]);
    assert!(o.status.success(), "{}", stderr(&o));
    let mut want = vec![live, remote, "rays.npy".to_string()];
    want.sort();
    assert_eq!(only_files(dir.path()), want);
}

#[test]
fn a_symlinked_output_is_written_where_it_points() {
    let dir = tempfile::tempdir().unwrap();
    std::fs::create_dir(dir.path().join("real")).unwrap();
    write(dir.path(), "real/r.npy", "old");
    std::os::unix::fs::symlink("real/r.npy", dir.path().join("link.npy")).unwrap();
    let o = raypipe(dir.path(), &["rays", "--size", "4x4", "-o", "link.npy"]);
    assert!(o.status.success(), "{}", stderr(&o));
    assert!(std::fs::symlink_metadata(dir.path().join("link.npy")).unwrap().file_type().is_symlink());
    assert!(std::fs::read(dir.path().join("real/r.npy")).unwrap().starts_with(b"\x93NUMPY"));
}

#[test]
fn a_full_disk_on_the_report_leaves_no_image_nor_waveform() {
    let dir = tempfile::tempdir().unwrap();
    // /dev/full answers every write with ENOSPC.
    let o =
        raypipe(dir.path(), &["simulate", "--size", "16x16", "-o", "a.png", "--vcd", "w.vcd", "--report", "/dev/full"]);
    assert_one_line_error(&o, "/dev/full");
    assert!(std::fs::metadata("/dev/full").unwrap().file_type().is_char_device());
    assert_eq!(only_files(dir.path()), Vec::<String>::new());
}
