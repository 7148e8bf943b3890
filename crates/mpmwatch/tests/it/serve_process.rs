//! `mpmwatch serve` as a child process on loopback ports the OS hands out.
//!
//! A port that was free when `free_port` picked it can be taken by a test running in parallel
//! before the child binds it. The child then exits ("Address already in use"), and a test that
//! only polls the HTTP port would wait out its hang guard. So the start watches the child while
//! it polls, and when the child has exited it starts it again on fresh ports, a bounded number
//! of times.

use std::path::Path;
use std::process::{Child, Command, ExitStatus, Stdio};
use std::time::Duration;

use crate::fault_support::free_port;
use crate::service_support::HANG_GUARD;

/// Starts on fresh ports; each failed start is a port race lost, rare, so three is plenty.
const ATTEMPTS: usize = 3;

/// How long the child must stay alive once its HTTP port answers. The answer could come from
/// another test's server that took the port first; ours then exits as soon as its bind fails.
const STAYS_UP: Duration = Duration::from_millis(500);

/// A running `mpmwatch serve`; killed (SIGKILL) and reaped when dropped, panics included.
pub struct Served {
    /// The child process.
    pub child: Child,
    /// Its zenoh listening port.
    pub zenoh: u16,
    /// Its HTTP port.
    pub http: u16,
}

impl Served {
    /// Kills the child now (`kill -9`: no shutdown, no final flush) and reaps it.
    pub fn kill(&mut self) {
        let _ = self.child.kill();
        let _ = self.child.wait();
    }
}

impl Drop for Served {
    fn drop(&mut self) {
        self.kill();
    }
}

/// Writes `config(zenoh_port, http_port)` to `path`, starts `mpmwatch serve --config path` with
/// stderr to `stderr`, and returns once the child listens on its HTTP port.
pub async fn serve(path: &Path, config: impl Fn(u16, u16) -> String, stderr: fn() -> Stdio) -> Served {
    for attempt in 1..=ATTEMPTS {
        let (zenoh, http) = (free_port(), free_port());
        std::fs::write(path, config(zenoh, http)).expect("write the config");
        let mut child = Command::new(env!("CARGO_BIN_EXE_mpmwatch"))
            .args(["serve", "--config"])
            .arg(path)
            .env("RUST_LOG", "warn")
            .stdout(Stdio::null())
            .stderr(stderr())
            .spawn()
            .expect("start mpmwatch serve");
        match listening(&mut child, http).await {
            Ok(()) => return Served { child, zenoh, http },
            Err(status) => eprintln!(
                "start {attempt} of {ATTEMPTS}: mpmwatch serve exited ({status}) before listening on \
                 127.0.0.1:{http}; trying fresh ports"
            ),
        }
    }
    panic!("mpmwatch serve exited before listening, {ATTEMPTS} times on fresh ports");
}

/// Waits until `http` answers and the child is still alive `STAYS_UP` later; `Err` with the
/// child's exit status if it exits first.
async fn listening(child: &mut Child, http: u16) -> Result<(), ExitStatus> {
    let deadline = tokio::time::Instant::now() + HANG_GUARD;
    loop {
        if let Some(status) = child.try_wait().expect("the child's status") {
            return Err(status);
        }
        if tokio::net::TcpStream::connect(("127.0.0.1", http)).await.is_ok() {
            tokio::time::sleep(STAYS_UP).await;
            return match child.try_wait().expect("the child's status") {
                Some(status) => Err(status),
                None => Ok(()),
            };
        }
        assert!(tokio::time::Instant::now() < deadline, "mpmwatch serve never listened on {http}");
        tokio::time::sleep(Duration::from_millis(100)).await;
    }
}
