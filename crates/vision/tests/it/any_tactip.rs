//! Any TacTip from its frames alone, on synthetic sensors whose truth is
//! known: a 331-pin sensor of concentric rings in 128 x 128 frames (pins of
//! a few pixels, a rim with specks) and a 127-pin hexagonal lattice in
//! 256 x 256 frames. Inspection must tell the layouts apart and count the
//! pins; the rest layout estimated from taps alone (no undeformed frame)
//! must lie within a fraction of a pixel of the truth; every pin must be
//! tracked, each to its own true position.

use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use tactrace_testdata::layouts::{hex_sensor, ring_sensor, SyntheticSensor};
use tactrace_vision::{
    draw_inspection, estimate_rest, inspect, Detection, DetectorParams, Frame, FrameDetector,
    Inspection, LayoutKind, PinReader, RestParams, SightParams,
};

/// A tap: a smooth push away from a contact point `at` (peak `push`
/// spacings-ish px at one kernel width), a swirl, and a small shift.
struct Tap {
    at: [f64; 2],
    width: f64,
    push: f64,
    swirl: f64,
    shift: [f64; 2],
}

impl Tap {
    fn random(rng: &mut ChaCha8Rng, s: &SyntheticSensor, strength: f64) -> Self {
        let reach = 0.6 * (s.rim[0] - 8.0);
        let (r, t) = (rng.random_range(0.0..reach), rng.random_range(0.0..6.3f64));
        let scale = s.rim[0] / 55.0;
        Tap {
            at: [s.centre[0] + r * t.cos(), s.centre[1] + r * t.sin()],
            width: scale * rng.random_range(10.0..16.0),
            push: strength * scale * rng.random_range(0.0..4.0),
            swirl: strength * scale * rng.random_range(-1.5..1.5),
            shift: [rng.random_range(-0.3..0.3), rng.random_range(-0.3..0.3)],
        }
    }

    fn moved(&self, p: [f64; 2]) -> [f64; 2] {
        let (dx, dy) = (p[0] - self.at[0], p[1] - self.at[1]);
        let g = (-(dx * dx + dy * dy) / (2.0 * self.width * self.width)).exp() / self.width;
        [
            p[0] + self.shift[0] + g * (self.push * dx - self.swirl * dy),
            p[1] + self.shift[1] + g * (self.push * dy + self.swirl * dx),
        ]
    }
}

/// The frame of `pins` (binary: white pins, rim and specks on black).
fn render(s: &SyntheticSensor, pins: &[[f64; 2]]) -> Frame {
    let mut frame = Frame::new(s.size, s.size);
    for p in pins.iter().chain(&s.specks) {
        let r = if s.specks.contains(p) {
            0.5
        } else {
            s.pin_radius
        };
        let (x0, x1) = ((p[0] - r).floor().max(0.0) as u32, (p[0] + r).ceil() as u32);
        let (y0, y1) = ((p[1] - r).floor().max(0.0) as u32, (p[1] + r).ceil() as u32);
        for y in y0..=y1.min(s.size - 1) {
            for x in x0..=x1.min(s.size - 1) {
                let d2 = (f64::from(x) - p[0]).powi(2) + (f64::from(y) - p[1]).powi(2);
                if d2 <= r * r {
                    frame.put_pixel(x, y, image::Luma([255]));
                }
            }
        }
    }
    for (x, y, v) in frame.enumerate_pixels_mut() {
        let (dx, dy) = (f64::from(x) - s.centre[0], f64::from(y) - s.centre[1]);
        let d = dx.hypot(dy);
        // Arcs: the rim with two gaps.
        if d >= s.rim[0] && d <= s.rim[1] && dy.atan2(dx).sin().abs() > 0.15 {
            *v = image::Luma([255]);
        }
    }
    frame
}

/// `n` taps of the sensor: the frames and the true pin positions.
fn taps(s: &SyntheticSensor, n: usize, seed: u64, strength: f64) -> Vec<(Frame, Vec<[f64; 2]>)> {
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    (0..n)
        .map(|_| {
            let tap = Tap::random(&mut rng, s, strength);
            let pins: Vec<[f64; 2]> = s.rest.iter().map(|&p| tap.moved(p)).collect();
            (render(s, &pins), pins)
        })
        .collect()
}

fn inspected(s: &SyntheticSensor, seed: u64) -> Inspection {
    let frames: Vec<Frame> = taps(s, 12, seed, 1.0).into_iter().map(|t| t.0).collect();
    inspect(&frames, None).expect("inspection")
}

fn detector(s: &SyntheticSensor, found: &Inspection) -> FrameDetector {
    SightParams {
        preprocess: found.preprocess.clone(),
        detect: found.detect.clone(),
    }
    .check(s.size, s.size)
    .expect("valid proposal")
}

fn mean_and_worst(errors: &[f64]) -> (f64, f64) {
    let worst = errors.iter().copied().fold(0.0, f64::max);
    (errors.iter().sum::<f64>() / errors.len() as f64, worst)
}

fn distance(a: [f64; 2], b: [f64; 2]) -> f64 {
    (a[0] - b[0]).hypot(a[1] - b[1])
}

/// Inspection tells concentric rings from a hexagonal lattice, counts the
/// pins, measures the spacing, picks the detector for the pin size, and
/// masks the rim and its specks while keeping every pin.
#[test]
fn inspection_tells_rings_from_a_lattice_and_counts_the_pins() {
    for (s, kind, spacing, small) in [
        (ring_sensor(), LayoutKind::Rings, 4.8, true),
        (hex_sensor(), LayoutKind::Hexagonal, 14.0, false),
    ] {
        let found = inspected(&s, 5);
        assert_eq!(found.layout.kind, kind);
        assert_eq!(found.pins, s.rest.len(), "{kind:?}");
        assert!(
            (found.spacing / spacing - 1.0).abs() < 0.1,
            "{kind:?} spacing {}",
            found.spacing
        );
        assert_eq!(matches!(found.detect, DetectorParams::Spots(_)), small);
        let mask = found.preprocess.mask.expect("a mask");
        assert!(distance(mask.centre, s.centre) < 0.5, "{mask:?}");
        let farthest = s
            .rest
            .iter()
            .map(|&p| distance(p, mask.centre))
            .fold(0.0, f64::max);
        assert!(mask.radius > farthest + s.pin_radius, "{kind:?}: {mask:?}");
        assert!(mask.radius < s.rim[0], "{kind:?}: {mask:?}");
        if small {
            assert!(
                s.specks
                    .iter()
                    .all(|&p| distance(p, mask.centre) > mask.radius),
                "{mask:?} keeps a speck"
            );
            assert_eq!(found.layout.rings.len(), 11, "{:?}", found.layout.rings);
        }
        let rim = found.rim.expect("the rim is seen");
        assert!(
            distance(rim.centre, s.centre) < 1.0 && rim.radius > s.rim[0] && rim.radius < s.rim[1]
        );
        // Binary frames need no threshold.
        assert!(found.binary && found.preprocess.threshold.is_none());
        // The picture: the inspected frame enlarged to at least 512 px, a
        // green cross on every pin it kept.
        assert_eq!(found.picture.pins.len(), s.rest.len());
        let frame = &taps(&s, 12, 5, 1.0)[found.picture.frame].0;
        let img = draw_inspection(frame, &found);
        let scale = img.width() / s.size;
        assert!(img.width() >= 512 && img.width() == scale * s.size);
        for p in &found.picture.pins {
            let (x, y) = (
                (p[0] + 0.5) * f64::from(scale),
                (p[1] + 0.5) * f64::from(scale),
            );
            assert_eq!(
                img.get_pixel(x as u32, y as u32).0,
                [40, 220, 80],
                "pin at {p:?}"
            );
        }
    }
}

/// With no undeformed frame, the rest layout estimated from 150 taps lies
/// within a fraction of a pixel of the true one (each true pin has one
/// estimated pin that close), its residual is reported, and the taps held
/// out are all fully tracked with every pin on its own true position.
#[test]
fn rest_layout_from_taps_alone_and_small_pins_fully_tracked() {
    for (s, seed) in [(ring_sensor(), 11), (hex_sensor(), 12)] {
        let found = inspected(&s, seed);
        let frames = detector(&s, &found);
        let fit = taps(&s, 150, seed + 100, 1.0);
        let detections: Vec<Detection> = fit
            .iter()
            .map(|(f, _)| {
                frames
                    .detect(&image::DynamicImage::ImageLuma8(f.clone()))
                    .expect("detect")
            })
            .collect();
        let est = estimate_rest(&detections, found.pins, &RestParams::default()).expect("rest");
        assert_eq!(est.pins.len(), s.rest.len());
        assert!(
            est.residual.is_finite() && est.residual < 1.0,
            "{}",
            est.residual
        );
        let errors: Vec<f64> = s
            .rest
            .iter()
            .map(|&t| {
                est.pins
                    .iter()
                    .map(|&e| distance(t, e))
                    .fold(f64::INFINITY, f64::min)
            })
            .collect();
        let (mean, worst) = mean_and_worst(&errors);
        assert!(
            worst < 0.45 && mean < 0.2,
            "rest error mean {mean:.3} worst {worst:.3} px"
        );
        // Held-out taps, twice as strong: every pin found, each on its own
        // true position (the estimated pin nearest to the true rest pin).
        let reader = PinReader::new(frames, est.pins.clone()).expect("reader");
        let truth_of: Vec<usize> = est
            .pins
            .iter()
            .map(|&e| {
                (0..s.rest.len())
                    .min_by(|&a, &b| distance(s.rest[a], e).total_cmp(&distance(s.rest[b], e)))
                    .expect("pins")
            })
            .collect();
        let held_out = taps(&s, 60, seed + 200, 1.5);
        let (mut full, mut split) = (0, 0);
        for (frame, pins) in &held_out {
            let read = reader
                .read(&image::DynamicImage::ImageLuma8(frame.clone()))
                .expect("read");
            full += usize::from(read.counts.fully_tracked());
            split += read.counts.split;
            for (k, p) in read.tracked.pins.iter().enumerate() {
                let d = distance(*p, pins[truth_of[k]]);
                assert!(
                    d < 0.5 * s.pin_radius.max(1.0),
                    "pin {k} is {d:.2} px from its own"
                );
            }
        }
        assert!(full >= 59, "{full} of 60 fully tracked");
        if s.size == 128 {
            // The small pins touch now and then: pins split from clusters.
            assert!(split > 0);
        }
    }
}

/// A raw colour camera frame (320 x 240 RGB: the dome lit unevenly, pins
/// as soft bright spots, a bright rim, sensor noise) of a 61-pin lattice,
/// the pins pushed by `tap`.
fn camera_frame(tap: &Tap, rng: &mut ChaCha8Rng) -> image::RgbImage {
    let centre = [170.3, 118.6];
    let mut pins = Vec::new();
    for q in -4i32..=4 {
        for r in -4i32..=4 {
            if (q + r).abs() <= 4 {
                let x = centre[0] + 16.0 * (f64::from(q) + 0.5 * f64::from(r));
                pins.push(tap.moved([x, centre[1] + 16.0 * 0.75f64.sqrt() * f64::from(r)]));
            }
        }
    }
    image::RgbImage::from_fn(320, 240, |x, y| {
        let (x, y) = (f64::from(x), f64::from(y));
        let d = (x - centre[0]).hypot(y - centre[1]);
        let mut v = 30.0 + x / 10.0 + y / 20.0;
        if (96.0..=102.0).contains(&d) {
            v += 150.0;
        }
        for p in &pins {
            let r2 = (x - p[0]).powi(2) + (y - p[1]).powi(2);
            if r2 < 100.0 {
                v += 140.0 * (-r2 / (2.0 * 2.2 * 2.2)).exp();
            }
        }
        v += rng.random_range(-3.0..3.0);
        let g = v.clamp(0.0, 255.0) as u8;
        image::Rgb([g.saturating_add(10), g, g.saturating_sub(10)])
    })
}

/// Raw colour frames in: inspection sees they are grey, proposes an
/// adaptive threshold and a mask inside the rim, counts the 61 pins of the
/// lattice; the frames read through that preprocessing (RGB or RGBA alike)
/// are fully tracked against the rest layout estimated from them.
#[test]
fn raw_colour_frames_inspected_and_read() {
    let mut rng = ChaCha8Rng::seed_from_u64(21);
    let lattice = SyntheticSensor {
        size: 320,
        centre: [170.3, 118.6],
        rest: Vec::new(),
        pin_radius: 3.0,
        rim: [96.0, 102.0],
        specks: Vec::new(),
    };
    let frames: Vec<image::RgbImage> = (0..40)
        .map(|_| {
            let tap = Tap::random(&mut rng, &lattice, 1.0);
            camera_frame(&tap, &mut rng)
        })
        .collect();
    let grey: Vec<Frame> = frames
        .iter()
        .take(12)
        .map(|f| tactrace_vision::preprocess::grey_of(&image::DynamicImage::ImageRgb8(f.clone())))
        .collect();
    let found = inspect(&grey, None).expect("inspection");
    assert!(!found.binary);
    assert!(matches!(
        found.preprocess.threshold,
        Some(tactrace_vision::Threshold::AdaptiveGaussian { c, .. }) if c < 0.0
    ));
    assert_eq!((found.pins, found.layout.kind), (61, LayoutKind::Hexagonal));
    let mask = found.preprocess.mask.expect("mask");
    assert!(mask.radius < 96.0 && mask.radius > 4.0 * 16.0, "{mask:?}");
    let reader_frames = SightParams {
        preprocess: found.preprocess.clone(),
        detect: found.detect.clone(),
    }
    .check(320, 240)
    .expect("valid");
    let detections: Vec<Detection> = frames
        .iter()
        .map(|f| {
            reader_frames
                .detect(&image::DynamicImage::ImageRgb8(f.clone()))
                .expect("detect")
        })
        .collect();
    let rest = estimate_rest(&detections, found.pins, &RestParams::default()).expect("rest");
    let reader = PinReader::new(reader_frames, rest.pins).expect("reader");
    for f in &frames {
        let rgb = reader
            .read(&image::DynamicImage::ImageRgb8(f.clone()))
            .expect("read");
        assert!(rgb.counts.fully_tracked(), "{:?}", rgb.counts);
        let rgba = image::DynamicImage::ImageRgb8(f.clone()).to_rgba8();
        let again = reader
            .read(&image::DynamicImage::ImageRgba8(rgba))
            .expect("read RGBA");
        assert_eq!(again, rgb);
    }
}
