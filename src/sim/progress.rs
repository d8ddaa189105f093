//! Progress of a run, per frame: a terminal bar, or one flushed stderr line per frame for logs
//! (a farm's per-task log shows where a shot is and when it will end), or nothing.

use std::io::IsTerminal;
use std::time::Instant;

/// How a run reports its frames.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum ProgressMode {
    /// An `indicatif` bar on stderr.
    Bar,
    /// `LABEL: frame F/N, S s/frame, K faces, ETA T` on stderr, one line per frame.
    Lines,
    None,
}

impl ProgressMode {
    /// The names on the command line.
    pub const NAMES: [&'static str; 3] = ["bar", "lines", "none"];

    pub fn parse(name: &str) -> Option<ProgressMode> {
        match name {
            "bar" => Some(ProgressMode::Bar),
            "lines" => Some(ProgressMode::Lines),
            "none" => Some(ProgressMode::None),
            _ => None,
        }
    }

    /// `--progress` as given, else `none` for `--quiet`, else a bar on a terminal and lines
    /// otherwise.
    pub fn choose(given: Option<&str>, quiet: bool) -> ProgressMode {
        match given.and_then(ProgressMode::parse) {
            Some(m) => m,
            None if quiet => ProgressMode::None,
            None if std::io::stderr().is_terminal() => ProgressMode::Bar,
            None => ProgressMode::Lines,
        }
    }
}

/// What a run reports to: the mode, the label of its lines and bar (the scene name, or a
/// batch's shot), and the bars of the other shots running beside it.
#[derive(Clone)]
pub struct Progress {
    pub mode: ProgressMode,
    /// Overrides the scene name as label.
    pub label: Option<String>,
    pub bars: Option<indicatif::MultiProgress>,
}

impl Progress {
    pub fn new(mode: ProgressMode) -> Progress {
        Progress { mode, label: None, bars: None }
    }
}

/// The report of one run in progress (frames `first..=last`).
pub(super) struct Reporter {
    mode: ProgressMode,
    label: String,
    bar: Option<indicatif::ProgressBar>,
    started: Instant,
    first: usize,
    last: usize,
    start_frame: usize,
    preroll: usize,
}

impl Reporter {
    /// `start_frame` is the number of the first written frame and `preroll` the frames
    /// simulated before it: the bar and the lines name frames as their files do.
    pub(super) fn start(
        p: &Progress,
        scene_name: &str,
        (first, last): (usize, usize),
        start_frame: usize,
        preroll: usize,
    ) -> Reporter {
        let label = p.label.clone().unwrap_or_else(|| scene_name.to_string());
        let bar = (p.mode == ProgressMode::Bar).then(|| {
            let bar = indicatif::ProgressBar::new(last as u64);
            let bar = match &p.bars {
                Some(multi) => multi.add(bar),
                None => bar,
            };
            // No {pos}/{len}: they count from the run's start, preroll included; the message
            // names the frame by its file number, as the lines do.
            bar.set_style(
                indicatif::ProgressStyle::with_template("{msg} [{bar:40}] {elapsed} elapsed, ETA {eta}")
                    .unwrap_or_else(|_| indicatif::ProgressStyle::default_bar()),
            );
            bar.set_position(first as u64);
            bar
        });
        let r = Reporter { mode: p.mode, label, bar, started: Instant::now(), first, last, start_frame, preroll };
        if let Some(bar) = &r.bar {
            bar.set_message(format!("{}: {}", r.label, r.frame_name(first)));
        }
        r
    }

    /// Frame `f` (counted from the run's start) as its file is numbered: `frame 1005/1030`, or
    /// `preroll frame 3/10`.
    fn frame_name(&self, f: usize) -> String {
        match f.checked_sub(self.preroll) {
            Some(w) => format!("frame {}/{}", self.start_frame + w, self.start_frame + self.last - self.preroll),
            None => format!("preroll frame {f}/{}", self.preroll),
        }
    }

    /// Frame `f` is written; it took `wall_s` and has `faces` faces.
    pub(super) fn frame(&self, f: usize, wall_s: f64, faces: usize) {
        if let Some(bar) = &self.bar {
            bar.set_position(f as u64);
            bar.set_message(format!("{}: {}", self.label, self.frame_name(f)));
        }
        if self.mode != ProgressMode::Lines {
            return;
        }
        let done = f + 1 - self.first;
        let mean = self.started.elapsed().as_secs_f64() / done as f64;
        let eta = mean * (self.last - f) as f64;
        // eprintln writes unbuffered: the line is in the log when the frame is on disk.
        eprintln!("{}: {}, {wall_s:.2} s/frame, {faces} faces, ETA {}", self.label, self.frame_name(f), clock(eta));
    }

    pub(super) fn finish(self) {
        if let Some(bar) = self.bar {
            bar.finish();
        }
    }
}

/// Seconds as `1h02m03s`, `2m03s` or `3s`.
fn clock(s: f64) -> String {
    let s = s.round() as u64;
    match (s / 3600, s / 60 % 60, s % 60) {
        (0, 0, sec) => format!("{sec}s"),
        (0, m, sec) => format!("{m}m{sec:02}s"),
        (h, m, sec) => format!("{h}h{m:02}m{sec:02}s"),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn frames_are_named_as_their_files() {
        let p = Progress::new(ProgressMode::None);
        let r = Reporter::start(&p, "shot", (0, 32), 1001, 2);
        assert_eq!(r.frame_name(1), "preroll frame 1/2");
        assert_eq!(r.frame_name(2), "frame 1001/1031");
        assert_eq!(r.frame_name(32), "frame 1031/1031");
    }

    #[test]
    fn clock_reads_as_hours_minutes_seconds() {
        assert_eq!(super::clock(3.4), "3s");
        assert_eq!(super::clock(123.0), "2m03s");
        assert_eq!(super::clock(3723.0), "1h02m03s");
    }
}
