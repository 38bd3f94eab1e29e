//! What `cargo fmu build` and `cargo fmu container` show while cargo builds: one line per target
//! with the crate it is at, cargo's own count of units (`12/45`), what is done and what is left,
//! and a time estimate once a crate of it is done; cargo's messages only with `-v`, or all of them
//! for the crate whose build failed. On a terminal the lines are indicatif progress bars; in a log
//! (CI, a pipe) one plain line per crate built, with the count of what is done and the time.

use indicatif::{MultiProgress, ProgressBar, ProgressDrawTarget, ProgressStyle};
use std::io::IsTerminal;
use std::sync::Mutex;
use std::time::{Duration, Instant};

/// The whole build's display: the targets' bars, the count of crate builds done.
pub struct Progress {
    multi: Option<MultiProgress>,
    /// `-v`: cargo's messages pass through as they come, no bars.
    pub verbose: bool,
    started: Instant,
    /// Crate builds (one `cargo rustc` each) in all, and done.
    total: usize,
    done: Mutex<usize>,
    /// Each target's time and crates, for the summary.
    finished: Mutex<Vec<(String, usize, f64)>>,
}

/// One target's chain of crate builds.
pub struct Job<'a> {
    progress: &'a Progress,
    bar: Option<ProgressBar>,
    pub target: String,
    crates: usize,
    done: usize,
    started: Instant,
}

impl Progress {
    /// A display for `total` crate builds: bars where stderr is a terminal (and not `verbose`).
    pub fn new(verbose: bool, total: usize) -> Progress {
        let multi = (!verbose && std::io::stderr().is_terminal())
            .then(|| MultiProgress::with_draw_target(ProgressDrawTarget::stderr_with_hz(4)));
        Progress {
            multi,
            verbose,
            started: Instant::now(),
            total,
            done: Mutex::new(0),
            finished: Mutex::new(Vec::new()),
        }
    }

    /// Starts the line of `target`, which builds `crates` crates one after the other.
    pub fn job(&self, target: &str, crates: usize) -> Job<'_> {
        let bar = self.multi.as_ref().map(|m| {
            let bar = m.add(ProgressBar::new(crates as u64));
            bar.set_style(
                ProgressStyle::with_template("{prefix:>32} [{bar:20}] {pos}/{len} crates {msg}")
                    .unwrap_or_else(|_| ProgressStyle::default_bar())
                    .progress_chars("=> "),
            );
            bar.set_prefix(target.to_string());
            bar.set_message("waiting for cargo");
            bar.enable_steady_tick(Duration::from_millis(500));
            bar
        });
        Job {
            progress: self,
            bar,
            target: target.to_string(),
            crates,
            done: 0,
            started: Instant::now(),
        }
    }

    /// Prints a line above the bars (or plainly without them).
    pub fn println(&self, line: &str) {
        match &self.multi {
            Some(m) => {
                let _ = m.println(line);
            }
            None => eprintln!("{line}"),
        }
    }

    /// The summary after the last build: crates, targets, time; each target's time.
    pub fn summary(&self, what: &str) {
        let finished = self.finished.lock().unwrap_or_else(|e| e.into_inner());
        if finished.is_empty() {
            return;
        }
        if let Some(m) = &self.multi {
            let _ = m.clear();
        }
        let per: Vec<String> = finished
            .iter()
            .map(|(t, n, s)| format!("{t} {n} in {}", clock(*s)))
            .collect();
        eprintln!(
            "fmu: built {} {what} for {} targets in {} ({})",
            finished.iter().map(|(_, n, _)| n).sum::<usize>(),
            finished.len(),
            clock(self.started.elapsed().as_secs_f64()),
            per.join("; ")
        );
    }
}

impl Job<'_> {
    /// Whether cargo's messages pass through (`-v`).
    pub fn verbose(&self) -> bool {
        self.progress.verbose
    }

    /// Prints a line above the bars.
    pub fn println(&self, line: &str) {
        self.progress.println(line);
    }

    /// `krate` starts building (its `k`-th of the target's crates, from 0).
    pub fn start(&self, krate: &str) {
        if let Some(bar) = &self.bar {
            bar.set_message(format!("{krate}: cargo starting"));
        }
    }

    /// cargo's own progress line of the running crate: `units` done of `of`, and the units it is
    /// compiling (`"syn, serde"`).
    pub fn units(&self, krate: &str, units: usize, of: usize, compiling: &str) {
        if let Some(bar) = &self.bar {
            let mut names = compiling.to_string();
            if names.len() > 40 {
                let mut cut = 40;
                while !names.is_char_boundary(cut) {
                    cut -= 1;
                }
                names.truncate(cut);
                names.push_str("...");
            }
            bar.set_message(format!("{krate}: {units}/{of} units {names}{}", self.estimate()));
        }
    }

    /// What is left of this target, from the time its finished crates took (the first one
    /// builds every dependency, so the estimate is high at first and falls).
    fn estimate(&self) -> String {
        if self.done == 0 {
            return String::new();
        }
        let per = self.started.elapsed().as_secs_f64() / self.done as f64;
        format!(" (about {} left)", clock(per * (self.crates - self.done) as f64))
    }

    /// `krate` was built in `seconds`.
    pub fn crate_done(&mut self, krate: &str, seconds: f64) {
        self.done += 1;
        let all = {
            let mut done = self.progress.done.lock().unwrap_or_else(|e| e.into_inner());
            *done += 1;
            *done
        };
        let line = format!(
            "fmu: [{all}/{}] built {krate} for {} in {} ({} in all)",
            self.progress.total,
            self.target,
            clock(seconds),
            clock(self.progress.started.elapsed().as_secs_f64())
        );
        match &self.bar {
            Some(bar) => {
                bar.inc(1);
                bar.set_message(self.estimate());
            }
            None if !self.progress.verbose => eprintln!("{line}"),
            None => {}
        }
    }

    /// The target is done: its bar ends with its time.
    pub fn finish(self) {
        let seconds = self.started.elapsed().as_secs_f64();
        if let Some(bar) = &self.bar {
            bar.finish_with_message(format!("done in {}", clock(seconds)));
        }
        self.progress.finished.lock().unwrap_or_else(|e| e.into_inner()).push((
            self.target.clone(),
            self.done,
            seconds,
        ));
    }
}

/// `75.2` as `1m 15s`, `9.4` as `9.4 s`.
pub fn clock(seconds: f64) -> String {
    if seconds < 60.0 {
        format!("{seconds:.1} s")
    } else {
        let s = seconds.round() as u64;
        format!("{}m {:02}s", s / 60, s % 60)
    }
}

/// cargo's progress line (`Building [=====>   ] 12/45: syn, serde(build)`), as the units done,
/// the units in all, and the names: `None` for any other line.
pub fn cargo_progress(line: &str) -> Option<(usize, usize, String)> {
    let rest = line.trim_start().strip_prefix("Building")?;
    let after_bar = rest.trim_start().strip_prefix('[')?;
    let (_, counts) = after_bar.split_once(']')?;
    let counts = counts.trim_start();
    let (numbers, names) = counts.split_once(':').unwrap_or((counts, ""));
    let (done, of) = numbers.trim().split_once('/')?;
    Some((done.parse().ok()?, of.parse().ok()?, names.trim().to_string()))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn cargos_progress_line_is_read() {
        assert_eq!(
            cargo_progress("    Building [=====>    ] 12/45: syn, serde(build)"),
            Some((12, 45, "syn, serde(build)".into()))
        );
        assert_eq!(
            cargo_progress("    Building [       ] 0/3"),
            Some((0, 3, String::new()))
        );
        assert_eq!(cargo_progress("   Compiling syn v2.0.1"), None);
        assert_eq!(clock(75.2), "1m 15s");
        assert_eq!(clock(9.44), "9.4 s");
    }
}
