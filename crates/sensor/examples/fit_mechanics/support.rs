//! Helpers of the mechanics fit: the real-field cache, label bins,
//! Nelder-Mead and the comparison figure.
use image::{Rgb, RgbImage};
use tactrace_sensor::{EdgeTap, Shear, TacTipModel};

/// A simulated field (px per pin) and the real one (None = untracked).
pub type Pair = (Vec<[f64; 2]>, Vec<Option<[f64; 2]>>);

/// Fewest frames in a bin that is compared.
pub const MIN_BIN: usize = 10;

/// One real frame: labels and tracked displacement (px) per model pin.
pub struct RealTap {
    /// N of `frame_N_0.png`: N % 5 picks the part (0 score, 1 select,
    /// 2-4 fit; docs/sensor-model.md).
    pub number: usize,
    pub tap: EdgeTap,
    pub disp: Vec<Option<[f64; 2]>>,
}

impl RealTap {
    /// |move_1|, |move_2| < 1 mm and |move_6| < 2 deg.
    pub fn low_shear(&self) -> bool {
        self.tap
            .shear
            .is_some_and(|s| s.dx_mm.abs() < 1.0 && s.dy_mm.abs() < 1.0 && s.drz_deg.abs() < 2.0)
    }
}

/// Read the cache written by the `real_fields` example.
pub fn load(path: &str) -> Option<(Vec<[f64; 2]>, Vec<RealTap>)> {
    let text = std::fs::read_to_string(path).ok()?;
    let mut lines = text.lines();
    let nums = |s: &str| -> Vec<f64> {
        s.split_whitespace()
            .map(|v| v.parse().unwrap_or(f64::NAN))
            .collect()
    };
    let head = lines.next()?;
    let r = nums(head.strip_prefix("rest")?);
    let rest: Vec<[f64; 2]> = r.chunks(2).map(|c| [c[0], c[1]]).collect();
    let mut taps = Vec::new();
    for line in lines {
        let (name, tail) = line.split_once(' ')?;
        let number = name
            .split('_')
            .nth(1)
            .and_then(|n| n.parse().ok())
            .unwrap_or(usize::MAX);
        let v = nums(tail);
        if v.len() != 7 + 2 * rest.len() {
            continue;
        }
        let disp = v[7..]
            .chunks(2)
            .map(|c| (c[0].is_finite() && c[1].is_finite()).then_some([c[0], c[1]]))
            .collect();
        let tap = EdgeTap {
            r_mm: v[0],
            theta_deg: v[1],
            dz_mm: v[2],
            shear: Some(Shear {
                dx_mm: v[3],
                dy_mm: v[4],
                drz_deg: v[5],
            }),
        };
        taps.push(RealTap { number, tap, disp });
    }
    Some((rest, taps))
}

/// Frames with similar labels: r in 2 mm bins, theta in 15 deg bins,
/// vertical offset in thirds of [-1, 1] mm, and their mean real field.
pub struct Bin {
    pub members: Vec<usize>,
    pub mean: Vec<Option<[f64; 2]>>,
    pub centre: [f64; 3],
    /// Mean r (mm), theta (deg) and vertical offset (mm) of the members.
    pub labels: [f64; 3],
}

pub fn bins(taps: &[RealTap]) -> Vec<Bin> {
    let key = |t: &EdgeTap| {
        let r = ((t.r_mm + 5.0) / 2.0).floor().clamp(0.0, 4.0) as usize;
        let a = ((t.theta_deg + 45.0) / 15.0).floor().clamp(0.0, 5.0) as usize;
        let z = ((t.dz_mm + 1.0) / (2.0 / 3.0)).floor().clamp(0.0, 2.0) as usize;
        (r * 6 + a) * 3 + z
    };
    let mut groups = vec![Vec::new(); 90];
    for (k, t) in taps.iter().enumerate() {
        groups[key(&t.tap)].push(k);
    }
    groups
        .into_iter()
        .enumerate()
        .filter(|(_, g)| g.len() >= MIN_BIN)
        .map(|(key, members)| {
            let pins = taps[members[0]].disp.len();
            let mut sum = vec![[0.0; 3]; pins];
            for &k in &members {
                for (s, d) in sum.iter_mut().zip(&taps[k].disp) {
                    if let Some(d) = d {
                        s[0] += d[0];
                        s[1] += d[1];
                        s[2] += 1.0;
                    }
                }
            }
            let mean = sum
                .iter()
                .map(|s| (s[2] > 0.0).then(|| [s[0] / s[2], s[1] / s[2]]))
                .collect();
            let (r, a, z) = (key / 18, (key / 3) % 6, key % 3);
            let centre = [
                -4.0 + 2.0 * r as f64,
                -37.5 + 15.0 * a as f64,
                -2.0 / 3.0 + 2.0 / 3.0 * z as f64,
            ];
            let mut labels = [0.0; 3];
            for &k in &members {
                let t = &taps[k].tap;
                labels[0] += t.r_mm / members.len() as f64;
                labels[1] += t.theta_deg / members.len() as f64;
                labels[2] += t.dz_mm / members.len() as f64;
            }
            Bin {
                members,
                mean,
                centre,
                labels,
            }
        })
        .collect()
}

/// Mean |displacement| (sim, real) per hexagonal ring, rings found by
/// sorting the rest pins by distance from the centre-most pin.
pub fn ring_profile(rest: &[[f64; 2]], pairs: &[Pair]) -> Vec<[f64; 2]> {
    let mean = rest.iter().fold([0.0; 2], |a, p| {
        [
            a[0] + p[0] / rest.len() as f64,
            a[1] + p[1] / rest.len() as f64,
        ]
    });
    let d = |p: &[f64; 2], q: &[f64; 2]| (p[0] - q[0]).hypot(p[1] - q[1]);
    let centre = rest
        .iter()
        .min_by(|a, b| d(a, &mean).total_cmp(&d(b, &mean)))
        .copied()
        .unwrap_or(mean);
    let mut order: Vec<usize> = (0..rest.len()).collect();
    order.sort_by(|&a, &b| d(&rest[a], &centre).total_cmp(&d(&rest[b], &centre)));
    let mut ring = vec![0usize; rest.len()];
    for (rank, &i) in order.iter().enumerate() {
        ring[i] = (0..20).find(|&k| rank < 1 + 3 * k * (k + 1)).unwrap_or(20);
    }
    let top = ring.iter().copied().max().unwrap_or(0);
    let mut acc = vec![[0.0; 3]; top + 1];
    for (sim, real) in pairs {
        for (i, (e, r)) in sim.iter().zip(real).enumerate() {
            if let Some(r) = r {
                acc[ring[i]][0] += e[0].hypot(e[1]);
                acc[ring[i]][1] += r[0].hypot(r[1]);
                acc[ring[i]][2] += 1.0;
            }
        }
    }
    acc.iter()
        .map(|a| [a[0] / a[2].max(1.0), a[1] / a[2].max(1.0)])
        .collect()
}

const SCALE: f64 = 2.0;
const ARROW_GAIN: f64 = 2.0;

fn line(img: &mut RgbImage, a: [f64; 2], b: [f64; 2], off: [f64; 2], colour: Rgb<u8>) {
    let steps = ((b[0] - a[0]).hypot(b[1] - a[1]) * SCALE * 2.0)
        .ceil()
        .max(1.0) as usize;
    for s in 0..=steps {
        let t = s as f64 / steps as f64;
        let x = off[0] + (a[0] + t * (b[0] - a[0])) * SCALE;
        let y = off[1] + (a[1] + t * (b[1] - a[1])) * SCALE;
        for (ox, oy) in [(0.0, 0.0), (1.0, 0.0), (0.0, 1.0), (1.0, 1.0)] {
            let (x, y) = (x + ox, y + oy);
            if x >= 0.0 && y >= 0.0 && (x as u32) < img.width() && (y as u32) < img.height() {
                img.put_pixel(x as u32, y as u32, colour);
            }
        }
    }
}

/// Rows = four bins (r -4, -2, 0, +2 mm at theta -7.5 deg, central depth
/// bin, falling back to any bin); columns = real mean field (green), the
/// simulated field (blue), both overlaid. Arrows x2, frame scaled x2.
pub fn draw_figure(
    model: &TacTipModel,
    bins: &[Bin],
    pairs: &[Pair],
    out: &str,
) -> Result<(), image::ImageError> {
    let wanted = [[-4.0, 22.5], [-2.0, -37.5], [0.0, -7.5], [2.0, 37.5]];
    let mut rows = Vec::new();
    for w in wanted {
        let pick = bins
            .iter()
            .position(|b| {
                (b.centre[0] - w[0]).abs() < 0.1
                    && (b.centre[1] - w[1]).abs() < 0.1
                    && b.centre[2].abs() < 0.1
            })
            .unwrap_or(0);
        rows.push(pick);
    }
    let panel = 256.0 * SCALE;
    let mut img = RgbImage::from_pixel(
        (3.0 * panel) as u32,
        (rows.len() as f64 * panel) as u32,
        Rgb([255, 255, 255]),
    );
    let rest = model.rest_pins();
    let (green, blue, grey) = (Rgb([0, 150, 0]), Rgb([20, 60, 230]), Rgb([150, 150, 150]));
    for (row, &b) in rows.iter().enumerate() {
        let y0 = row as f64 * panel;
        let (sim, real) = &pairs[b];
        for col in 0..3 {
            let off = [col as f64 * panel, y0];
            for x in 0..panel as u32 {
                img.put_pixel(off[0] as u32 + x, y0 as u32, grey);
                img.put_pixel(
                    off[0] as u32 + x.min(panel as u32 - 1),
                    (y0 + panel - 1.0) as u32,
                    grey,
                );
            }
            for y in 0..panel as u32 {
                img.put_pixel(off[0] as u32, y0 as u32 + y, grey);
            }
            for (i, r) in rest.iter().enumerate() {
                line(
                    &mut img,
                    [r[0] - 0.5, r[1]],
                    [r[0] + 0.5, r[1]],
                    off,
                    Rgb([0, 0, 0]),
                );
                if col != 1 {
                    if let Some(d) = real[i] {
                        let tip = [r[0] + ARROW_GAIN * d[0], r[1] + ARROW_GAIN * d[1]];
                        line(&mut img, *r, tip, off, green);
                    }
                }
                if col != 0 {
                    let d = sim[i];
                    let tip = [r[0] + ARROW_GAIN * d[0], r[1] + ARROW_GAIN * d[1]];
                    line(&mut img, *r, tip, off, blue);
                }
            }
        }
        let c = bins[b].centre;
        println!(
            "figure row {row}: bin r {:+.1} mm, theta {:+.1} deg, dz {:+.2} mm ({} frames)",
            c[0],
            c[1],
            c[2],
            bins[b].members.len()
        );
    }
    img.save(out)
}

/// Running sums comparing a real displacement field with a simulated one,
/// pin by pin (px): their dot product and norms (cosine), the squared
/// difference (RMS), the mean magnitudes (ratio) and the largest real one.
#[derive(Debug, Default, Clone, Copy)]
pub struct FieldSums {
    pub dot: f64,
    pub real_sq: f64,
    pub sim_sq: f64,
    pub diff_sq: f64,
    pub real_abs: f64,
    pub sim_abs: f64,
    pub real_max: f64,
    pub count: f64,
}

impl FieldSums {
    /// Add one pin: real displacement `d`, simulated `e`.
    pub fn add(&mut self, d: [f64; 2], e: [f64; 2]) {
        self.dot += d[0] * e[0] + d[1] * e[1];
        self.real_sq += d[0] * d[0] + d[1] * d[1];
        self.sim_sq += e[0] * e[0] + e[1] * e[1];
        self.diff_sq += (d[0] - e[0]).powi(2) + (d[1] - e[1]).powi(2);
        self.real_abs += d[0].hypot(d[1]);
        self.sim_abs += e[0].hypot(e[1]);
        self.real_max = self.real_max.max(d[0].hypot(d[1]));
        self.count += 1.0;
    }

    /// Cosine between the two fields.
    pub fn cosine(&self) -> f64 {
        self.dot / (self.real_sq.sqrt() * self.sim_sq.sqrt()).max(1e-12)
    }
}
