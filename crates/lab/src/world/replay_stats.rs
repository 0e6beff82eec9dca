//! How far the real-frame world's answers were from the poses the loop
//! reached, and whether the bank held frames the model was trained on
//! (`metrics.json`'s `replay`, and the run's warnings).
use serde::Serialize;
use tactrace_sensor::{Answer, EdgeLabels, FrameBank, LabelScales};
use tactrace_store::TrainingRecord;

/// How far the answered frames were from the poses the loop reached.
#[derive(Debug, Clone, Serialize)]
pub struct ReplayStats {
    /// Frames in the bank.
    pub bank_frames: usize,
    /// Taps answered.
    pub taps: usize,
    /// Distinct frames answered.
    pub distinct_frames: usize,
    /// The metric's scales (label units per unit distance).
    pub scales: LabelScales,
    /// Scaled label distance of the answered frames: mean, 95th
    /// percentile, largest.
    pub distance_mean: f64,
    pub distance_p95: f64,
    pub distance_max: f64,
    /// Mean absolute label differences, mm / deg / mm.
    pub mean_abs_dr_mm: f64,
    pub mean_abs_dtheta_deg: f64,
    pub mean_abs_ddz_mm: f64,
    /// Taps answered by a frame further than `far_distance`.
    pub far_taps: usize,
    pub far_distance: f64,
    /// Bank frames the model was trained on (by image name; `None`: the
    /// model folder does not say which frames it was trained on).
    pub bank_frames_seen_in_training: Option<usize>,
    /// Taps answered by such a frame.
    pub taps_answered_by_training_frames: Option<usize>,
}

impl ReplayStats {
    /// The statistics of `answers` from `bank`.
    pub fn of(answers: &[Answer], bank: &FrameBank, far_distance: f64) -> Self {
        let n = answers.len().max(1) as f64;
        let mut d: Vec<f64> = answers.iter().map(|a| a.distance).collect();
        d.sort_by(f64::total_cmp);
        let p95 = d
            .get(((d.len() as f64 * 0.95).ceil() as usize).saturating_sub(1))
            .copied()
            .unwrap_or(0.0);
        let got = |a: &Answer| bank.frames()[a.frame].labels;
        let mean_abs = |f: &dyn Fn(&EdgeLabels) -> f64| {
            answers
                .iter()
                .map(|a| (f(&a.wanted) - f(&got(a))).abs())
                .sum::<f64>()
                / n
        };
        let mut distinct: Vec<usize> = answers.iter().map(|a| a.frame).collect();
        distinct.sort_unstable();
        distinct.dedup();
        Self {
            bank_frames: bank.frames().len(),
            taps: answers.len(),
            distinct_frames: distinct.len(),
            scales: bank.scales(),
            distance_mean: d.iter().sum::<f64>() / n,
            distance_p95: p95,
            distance_max: d.last().copied().unwrap_or(0.0),
            mean_abs_dr_mm: mean_abs(&|l| l.r_mm),
            mean_abs_dtheta_deg: mean_abs(&|l| l.theta_deg),
            mean_abs_ddz_mm: mean_abs(&|l| l.dz_mm),
            far_taps: answers.iter().filter(|a| a.distance > far_distance).count(),
            far_distance,
            bank_frames_seen_in_training: None,
            taps_answered_by_training_frames: None,
        }
    }

    /// The statistics with the bank frames and answered taps that were
    /// frames the model trained on (`training`, from its folder).
    pub fn with_training(
        mut self,
        training: Option<&TrainingRecord>,
        answers: &[Answer],
        bank: &FrameBank,
    ) -> Self {
        let Some(seen) = training.and_then(TrainingRecord::real_frames_seen) else {
            return self;
        };
        let trained: Vec<bool> = bank
            .frames()
            .iter()
            .map(|f| {
                f.path
                    .file_name()
                    .is_some_and(|n| seen.contains(&*n.to_string_lossy()))
            })
            .collect();
        self.bank_frames_seen_in_training = Some(trained.iter().filter(|&&t| t).count());
        self.taps_answered_by_training_frames =
            Some(answers.iter().filter(|a| trained[a.frame]).count());
        self
    }

    /// One line for the run's summary.
    pub fn summary(&self) -> String {
        format!(
            "label distance of the answered real frames: mean {:.3}, p95 {:.3}, max {:.3} \
             (mean |dr| {:.2} mm, |dtheta| {:.2} deg, |ddz| {:.2} mm; {} distinct of {} frames)",
            self.distance_mean,
            self.distance_p95,
            self.distance_max,
            self.mean_abs_dr_mm,
            self.mean_abs_dtheta_deg,
            self.mean_abs_ddz_mm,
            self.distinct_frames,
            self.bank_frames
        )
    }

    /// The warnings, as one: taps that reached poses the labels do not
    /// cover, and bank frames the model was trained on.
    pub fn warning(&self) -> Option<String> {
        let far = (self.far_taps > 0).then(|| {
            format!(
                "{} of {} taps were answered by a real frame more than {} label spreads from \
                 the pose reached (up to {:.2}): the collection's labels do not cover the \
                 poses this run reached, and those taps say little",
                self.far_taps, self.taps, self.far_distance, self.distance_max
            )
        });
        let seen = self
            .bank_frames_seen_in_training
            .filter(|&k| k > 0)
            .map(|k| {
                format!(
                    "{k} of the bank's {} frames (answering {} of {} taps) are frames the model \
                 was trained on: the run is judged on frames it was fitted to; answer with \
                 held-out frames only (--replay-keep, or --targets listing them)",
                    self.bank_frames,
                    self.taps_answered_by_training_frames.unwrap_or(0),
                    self.taps
                )
            });
        let all: Vec<String> = far.into_iter().chain(seen).collect();
        (!all.is_empty()).then(|| all.join("; "))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::path::Path;
    use tactrace_sensor::LabelledFrame;

    fn labels(r: f64, t: f64) -> EdgeLabels {
        EdgeLabels {
            r_mm: r,
            theta_deg: t,
            dz_mm: 0.0,
        }
    }

    #[test]
    fn bank_frames_the_model_trained_on_are_counted_and_said() {
        let names = ["frame_1_0.png", "frame_2_0.png", "frame_3_0.png"];
        let frames = names
            .iter()
            .zip([labels(-1.0, 0.0), labels(0.0, 5.0), labels(1.0, 10.0)])
            .map(|(n, labels)| LabelledFrame {
                path: Path::new("frames").join(n),
                labels,
            })
            .collect();
        let bank = FrameBank::new(frames, false).unwrap();
        let answer = |frame| Answer {
            wanted: labels(0.0, 0.0),
            frame,
            distance: 0.1,
        };
        let answers = [answer(0), answer(1), answer(1), answer(2)];
        let mut data = crate::test_data::edge_data(vec![0.0; 4], vec![0.0; 4], &[[0.0, 0.0]]);
        data.meta.source = "real".into();
        data.meta.images = vec!["frame_2_0.png".into(), "frame_9_0.png".into()];
        let record = TrainingRecord::all_rows(&data, None);
        let s = ReplayStats::of(&answers, &bank, 0.5);
        assert_eq!(s.bank_frames_seen_in_training, None, "unknown");
        assert!(s.warning().is_none());
        let s = s.with_training(Some(&record), &answers, &bank);
        assert_eq!(s.bank_frames_seen_in_training, Some(1));
        assert_eq!(s.taps_answered_by_training_frames, Some(2));
        let w = s.warning().unwrap();
        assert!(w.starts_with("1 of the bank's 3 frames (answering 2 of 4 taps) are frames the model was trained on"), "{w}");
    }

    /// Twenty answers at distances 0.05, 0.10, ..., 1.00 from two frames.
    #[test]
    fn the_statistics_are_those_of_the_answers() {
        let frames = [labels(-1.0, 0.0), labels(1.0, 10.0)]
            .map(|labels| LabelledFrame {
                path: "f.png".into(),
                labels,
            })
            .to_vec();
        let bank = FrameBank::new(frames, false).unwrap();
        let answers: Vec<Answer> = (1..=20)
            .map(|k| Answer {
                wanted: labels(-1.0 + 0.1 * k as f64, 0.0),
                frame: k % 2,
                distance: 0.05 * k as f64,
            })
            .collect();
        let s = ReplayStats::of(&answers, &bank, 0.5);
        assert!((s.distance_mean - 0.525).abs() < 1e-12, "{s:?}");
        assert!((s.distance_p95 - 0.95).abs() < 1e-12, "{s:?}");
        assert!((s.distance_max - 1.0).abs() < 1e-12, "{s:?}");
        assert_eq!((s.taps, s.distinct_frames, s.bank_frames), (20, 2, 2));
        assert_eq!(s.far_taps, 10, "0.55 .. 1.00");
        assert!(s.warning().is_some_and(|w| w.contains("10 of 20 taps")));
        // |dr|: wanted -1 + 0.1 k against -1 (k even) or +1 (k odd).
        let dr: f64 = (1..=20)
            .map(|k| {
                let got = if k % 2 == 0 { -1.0 } else { 1.0 };
                (-1.0 + 0.1 * k as f64 - got).abs()
            })
            .sum::<f64>()
            / 20.0;
        assert!((s.mean_abs_dr_mm - dr).abs() < 1e-12);
        assert!((s.mean_abs_dtheta_deg - 5.0).abs() < 1e-12);
    }
}
