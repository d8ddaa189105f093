//! The chaos floor with a spread: K reference runs from independently jittered initial positions,
//! each measured against the reference like any mode. Per compared frame and per measure, the
//! floor is the K errors' mean μ_f and sample standard deviation σ_f; over the run, the mean μ
//! and standard deviation σ of the K runs' frame-averaged errors. A mode's error ē (averaged
//! over the same frames) is within the floor band when ē ≤ μ + 2σ, and otherwise (ē − μ)/σ
//! standard deviations above it; its multiple is ē / μ. Frame by frame, the count of frames
//! whose error exceeds μ_f + 2σ_f says whether the excess is steady or comes from a few frames.

use serde::Serialize;

use super::{Errors, FrameErrors};
use crate::math::Real;

/// One scalar error measure: its name (as in the report) and how to read it from a frame.
pub struct Measure {
    pub name: &'static str,
    pub get: fn(&FrameErrors) -> Real,
}

/// Every measure that gets a band, a multiple and a verdict.
pub const MEASURES: [Measure; 8] = [
    Measure { name: "normal_deg", get: |e| e.visible.normal_deg },
    Measure { name: "normal_flat_deg", get: |e| e.visible.normal_flat_deg },
    Measure { name: "silhouette", get: |e| e.visible.silhouette },
    Measure { name: "depth", get: |e| e.visible.depth },
    Measure { name: "distance_mean", get: |e| e.geometric.mean },
    Measure { name: "distance_p95", get: |e| e.geometric.p95 },
    Measure { name: "visible_distance_mean", get: |e| e.geometric_visible.mean },
    Measure { name: "visible_distance_p95", get: |e| e.geometric_visible.p95 },
];

/// The floor of one measure.
#[derive(Clone, Debug, Serialize)]
pub struct MeasureBand {
    pub measure: &'static str,
    /// Per compared frame (`FloorBand::frames`): mean and sample standard deviation over the
    /// floor runs.
    pub per_frame_mean: Vec<Real>,
    pub per_frame_std: Vec<Real>,
    /// Over the runs' frame-averaged errors.
    pub mean: Real,
    pub std: Real,
}

/// The floor of every measure.
#[derive(Clone, Debug, Serialize)]
pub struct FloorBand {
    pub runs: usize,
    /// The frames every floor run compared.
    pub frames: Vec<usize>,
    pub measures: Vec<MeasureBand>,
}

/// A run's error in one measure against the floor band.
#[derive(Clone, Debug, Serialize)]
pub struct Verdict {
    pub measure: &'static str,
    /// Mean over the band's frames.
    pub error: Real,
    /// error / floor mean (infinite when the floor mean is 0 and the error not).
    pub multiple: Real,
    /// (error − floor mean) / floor std; infinite when the std is 0 and the error above the mean.
    pub sigmas: Real,
    /// error ≤ floor mean + 2 std.
    pub within: bool,
    /// Frames whose error exceeds that frame's mean + 2 std, of `frames`.
    pub frames_above: usize,
    pub frames: usize,
}

/// Mean and sample standard deviation (n − 1; 0 for fewer than two values).
pub fn mean_std(x: &[Real]) -> (Real, Real) {
    let n = x.len();
    if n == 0 {
        return (0.0, 0.0);
    }
    let mean = x.iter().sum::<Real>() / n as Real;
    if n < 2 {
        return (mean, 0.0);
    }
    let var = x.iter().map(|v| (v - mean) * (v - mean)).sum::<Real>() / (n - 1) as Real;
    (mean, var.sqrt())
}

/// The value of `m` at `frame` in `e`, if `e` compared that frame.
fn at(e: &Errors, frame: usize, m: &Measure) -> Option<Real> {
    e.per_frame.iter().find(|f| f.frame == frame).map(|f| (m.get)(f))
}

/// The band of the floor runs' errors; None without floor runs.
pub fn floor_band(floors: &[&Errors]) -> Option<FloorBand> {
    let first = floors.first()?;
    let frames: Vec<usize> = first
        .per_frame
        .iter()
        .map(|f| f.frame)
        .filter(|&f| floors.iter().all(|e| e.per_frame.iter().any(|g| g.frame == f)))
        .collect();
    let measures = MEASURES
        .iter()
        .map(|m| {
            let (mut per_frame_mean, mut per_frame_std) = (Vec::new(), Vec::new());
            for &f in &frames {
                let values: Vec<Real> = floors.iter().filter_map(|e| at(e, f, m)).collect();
                let (mu, sigma) = mean_std(&values);
                per_frame_mean.push(mu);
                per_frame_std.push(sigma);
            }
            let run_means: Vec<Real> = floors.iter().map(|e| frame_mean(e, &frames, m)).collect();
            let (mean, std) = mean_std(&run_means);
            MeasureBand { measure: m.name, per_frame_mean, per_frame_std, mean, std }
        })
        .collect();
    Some(FloorBand { runs: floors.len(), frames, measures })
}

/// Mean of `m` over those of `frames` that `e` compared.
fn frame_mean(e: &Errors, frames: &[usize], m: &Measure) -> Real {
    let values: Vec<Real> = frames.iter().filter_map(|&f| at(e, f, m)).collect();
    mean_std(&values).0
}

/// The run's error in every measure against the band (module doc).
pub fn verdicts(band: &FloorBand, e: &Errors) -> Vec<Verdict> {
    MEASURES
        .iter()
        .zip(&band.measures)
        .map(|(m, b)| {
            let error = frame_mean(e, &band.frames, m);
            let ratio = |a: Real, b: Real| {
                if b > 0.0 {
                    a / b
                } else if a > 0.0 {
                    Real::INFINITY
                } else {
                    0.0
                }
            };
            let frames_above = band
                .frames
                .iter()
                .enumerate()
                .filter(|&(k, &f)| at(e, f, m).is_some_and(|v| v > b.per_frame_mean[k] + 2.0 * b.per_frame_std[k]))
                .count();
            Verdict {
                measure: m.name,
                error,
                multiple: ratio(error, b.mean),
                sigmas: ratio(error - b.mean, b.std),
                within: error <= b.mean + 2.0 * b.std,
                frames_above,
                frames: band.frames.len(),
            }
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Errors whose normal angle is `normal[k]` in frame k + 1 (every other measure 0).
    fn errors(normal: &[Real]) -> Errors {
        let per_frame = normal
            .iter()
            .enumerate()
            .map(|(k, &n)| {
                let mut f = FrameErrors { frame: k + 1, ..Default::default() };
                f.visible.normal_deg = n;
                f
            })
            .collect();
        Errors { per_frame, ..Default::default() }
    }

    #[test]
    fn mean_and_sample_standard_deviation() {
        assert_eq!(mean_std(&[2.0, 4.0, 6.0]), (4.0, 2.0));
        assert_eq!(mean_std(&[3.0]), (3.0, 0.0));
        assert_eq!(mean_std(&[]), (0.0, 0.0));
    }

    #[test]
    fn band_and_verdicts_follow_the_floor_runs() {
        // Three floor runs over two frames: frame means 2 and 4; per frame std 1 and 2.
        let floors = [errors(&[1.0, 2.0]), errors(&[2.0, 4.0]), errors(&[3.0, 6.0])];
        let band = floor_band(&floors.iter().collect::<Vec<_>>()).unwrap();
        assert_eq!((band.runs, band.frames.clone()), (3, vec![1, 2]));
        let b = &band.measures[0];
        assert_eq!((b.per_frame_mean.clone(), b.per_frame_std.clone()), (vec![2.0, 4.0], vec![1.0, 2.0]));
        // Run means 1.5, 3, 4.5: mean 3, std 1.5.
        assert_eq!((b.mean, b.std), (3.0, 1.5));
        // Mean 5.5 ≤ 3 + 2·1.5 = 6: within; frame 1 (4.5 > 2 + 2·1) is above its band, frame 2
        // (6.5 ≤ 4 + 2·2) not.
        let v = &verdicts(&band, &errors(&[4.5, 6.5]))[0];
        assert!(v.within && v.multiple == 5.5 / 3.0 && v.frames_above == 1, "{v:?}");
        assert!((v.sigmas - 2.5 / 1.5).abs() < 1e-12, "{v:?}");
        // Mean 9: 4σ above, both frames above.
        let v = &verdicts(&band, &errors(&[6.0, 12.0]))[0];
        assert!(!v.within && v.sigmas == 4.0 && v.frames_above == 2 && v.multiple == 3.0, "{v:?}");
        // The other measures: all 0, a zero error is within and 0 times.
        let v = &verdicts(&band, &errors(&[6.0, 12.0]))[4];
        assert_eq!((v.measure, v.within, v.multiple, v.sigmas), ("distance_mean", true, 0.0, 0.0));
    }
}
