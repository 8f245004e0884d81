//! The agent processes a launcher starts: each started with the launcher as its parent (on
//! Linux it dies with it), checked while the flight runs and started again when it exits
//! early ([`Children::restart_exited`]), and ended by its id on every path out — success,
//! failure, Ctrl-C, or a panic (the guard's drop) — so no process outlives the launcher.

use std::ffi::OsString;
use std::path::PathBuf;
use std::process::{Child, Command, ExitStatus};
use std::time::{Duration, Instant};

use anyhow::{bail, Context, Result};

/// How to start a process again.
#[derive(Debug, Clone)]
pub struct Recipe {
    /// The program.
    pub program: PathBuf,
    /// Its arguments.
    pub args: Vec<OsString>,
    /// Variables added to its environment (a flight's key: in the environment, not the
    /// arguments, which every user of the machine can list).
    pub env: Vec<(OsString, OsString)>,
}

impl Recipe {
    fn command(&self) -> Command {
        let mut cmd = Command::new(&self.program);
        cmd.args(&self.args).envs(self.env.iter().map(|(k, v)| (k, v))).stdin(std::process::Stdio::null());
        cmd
    }
}

/// A process that exited early, and whether it was started again.
#[derive(Debug, Clone)]
pub struct Exited {
    /// The process's name in messages.
    pub label: String,
    /// How it exited.
    pub status: ExitStatus,
    /// Started again (its restart number from 1), or not (no restarts left, or it could not
    /// be started: why).
    pub restarted: std::result::Result<u32, String>,
}

/// Processes started by this one.
#[derive(Debug, Default)]
pub struct Children {
    procs: Vec<(String, Child, Recipe, u32)>,
}

impl Children {
    /// Starts `recipe`, named `label` in messages.
    pub fn spawn(&mut self, recipe: Recipe, label: String) -> Result<()> {
        let child = recipe.command().spawn().with_context(|| format!("cannot start {label}"))?;
        self.procs.push((label, child, recipe, 0));
        Ok(())
    }

    /// Starts again every process that has exited, while it has been restarted fewer than
    /// `limit` times; what exited.
    pub fn restart_exited(&mut self, limit: u32) -> Vec<Exited> {
        let mut out = Vec::new();
        for (label, child, recipe, restarts) in &mut self.procs {
            let Ok(Some(status)) = child.try_wait() else { continue };
            let restarted = match *restarts < limit {
                false => Err(format!("no restarts left ({limit})")),
                true => match recipe.command().spawn() {
                    Ok(c) => {
                        *child = c;
                        *restarts += 1;
                        Ok(*restarts)
                    }
                    Err(e) => Err(format!("cannot start it again: {e}")),
                },
            };
            if restarted.is_err() {
                // Reported once: from now on it is one that will not come back.
                *restarts = u32::MAX;
            }
            if restarted.is_ok() || *restarts == u32::MAX {
                out.push(Exited { label: label.clone(), status, restarted });
            }
        }
        // A process given up on (exited, reaped) is not reported again.
        self.procs.retain(|(_, _, _, r)| *r != u32::MAX);
        out
    }

    /// The process ids.
    pub fn pids(&self) -> Vec<u32> {
        self.procs.iter().map(|(_, c, _, _)| c.id()).collect()
    }

    /// CPU time used so far (s) and peak resident memory (bytes) of every process still
    /// running, from `/proc` (Linux; empty elsewhere).
    pub fn usage(&self) -> Vec<(f64, u64)> {
        self.procs.iter().filter_map(|(_, c, _, _)| usage_of(c.id())).collect()
    }

    /// An error if any process has exited (before it was told to).
    pub fn check(&mut self) -> Result<()> {
        for (label, child, _, _) in &mut self.procs {
            if let Some(status) = child.try_wait().with_context(|| format!("cannot wait for {label}"))? {
                bail!("{label} exited early ({status})");
            }
        }
        Ok(())
    }

    /// Waits up to `grace` for every process to exit, then kills the rest (by id) and reaps them.
    /// Returns how many had to be killed.
    pub fn finish(&mut self, grace: Duration) -> usize {
        let start = Instant::now();
        while start.elapsed() < grace && self.procs.iter_mut().any(|(_, c, _, _)| matches!(c.try_wait(), Ok(None))) {
            std::thread::sleep(Duration::from_millis(20));
        }
        let mut killed = 0;
        for (_, child, _, _) in &mut self.procs {
            if matches!(child.try_wait(), Ok(None)) {
                let _ = child.kill();
                killed += 1;
            }
            let _ = child.wait();
        }
        self.procs.clear();
        killed
    }
}

impl Drop for Children {
    fn drop(&mut self) {
        self.finish(Duration::ZERO);
    }
}

/// CPU time (s, the scheduler's own nanosecond counts summed over every thread) and peak
/// resident memory (bytes, `VmHWM`) of process `pid`.
fn usage_of(pid: u32) -> Option<(f64, u64)> {
    let mut cpu_ns = 0u64;
    for task in std::fs::read_dir(format!("/proc/{pid}/task")).ok()?.flatten() {
        let sched = std::fs::read_to_string(task.path().join("schedstat")).unwrap_or_default();
        cpu_ns += sched.split_whitespace().next().and_then(|v| v.parse::<u64>().ok()).unwrap_or(0);
    }
    let status = std::fs::read_to_string(format!("/proc/{pid}/status")).ok()?;
    let hwm_kib: u64 = status.lines().find(|l| l.starts_with("VmHWM:"))?.split_whitespace().nth(1)?.parse().ok()?;
    Some((cpu_ns as f64 * 1e-9, hwm_kib * 1024))
}
