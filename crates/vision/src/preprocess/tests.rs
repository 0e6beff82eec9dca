//! Theory tests of the preprocessing stage: what each step must do on
//! frames whose answer is known without running it.

use super::*;

fn white(width: u32, height: u32) -> DynamicImage {
    DynamicImage::ImageLuma8(Frame::from_pixel(width, height, image::Luma([255])))
}

fn stage(params: PreprocessParams, width: u32, height: u32) -> PreprocessStage {
    params
        .check()
        .expect("valid")
        .stage(width, height)
        .expect("fits")
}

/// A mask of radius R keeps exactly the pixels whose centre lies within R
/// of its centre, for centres on and off the pixel grid, inside and
/// partly outside the frame.
#[test]
fn mask_keeps_exactly_the_pixels_within_its_radius() {
    for (centre, radius) in [
        ([20.0, 15.0], 7.0),
        ([20.3, 14.6], 7.5),
        ([0.0, 0.0], 10.0),
        ([33.7, 2.2], 12.25),
        ([20.0, 15.0], 0.5),
    ] {
        let mask = MaskCircle { centre, radius };
        let p = PreprocessParams {
            mask: Some(mask),
            ..PreprocessParams::default()
        };
        let out = stage(p, 40, 30).apply(&white(40, 30)).expect("apply");
        for (x, y, v) in out.enumerate_pixels() {
            let d2 = (f64::from(x) - centre[0]).powi(2) + (f64::from(y) - centre[1]).powi(2);
            let want = if d2 <= radius * radius { 255 } else { 0 };
            assert_eq!(v[0], want, "({x}, {y}) for {mask:?}");
        }
    }
}

/// On a constant frame every pixel equals its neighbourhood mean, so the
/// adaptive threshold `v - mean > -ceil(C)` is all white when C > 0 and
/// all black when C <= 0, for both weightings and any block.
#[test]
fn adaptive_threshold_of_a_constant_frame() {
    for level in [0u8, 93, 255] {
        let frame = Frame::from_pixel(23, 17, image::Luma([level]));
        for block in [3u32, 5, 7, 11, 61] {
            for c in [-5.0, -0.5, 0.0, 0.2, 3.0] {
                for t in [
                    Threshold::AdaptiveMean { block, c },
                    Threshold::AdaptiveGaussian { block, c },
                ] {
                    let want = if c > 0.0 { 255 } else { 0 };
                    let out = threshold(&frame, t);
                    assert!(out.pixels().all(|p| p[0] == want), "{t:?} level {level}");
                }
            }
        }
    }
}

/// A bright spot on a dark ground: white with C = -5 where it is more
/// than 5 levels above its neighbourhood, the ground stays black.
#[test]
fn adaptive_threshold_finds_a_bright_spot() {
    let mut frame = Frame::from_pixel(40, 40, image::Luma([60]));
    for y in 18..21 {
        for x in 18..21 {
            frame.put_pixel(x, y, image::Luma([140]));
        }
    }
    for t in [
        Threshold::AdaptiveMean { block: 11, c: -5.0 },
        Threshold::AdaptiveGaussian { block: 11, c: -5.0 },
    ] {
        let out = threshold(&frame, t);
        let whites: Vec<(u32, u32)> = out
            .enumerate_pixels()
            .filter(|p| p.2[0] == 255)
            .map(|p| (p.0, p.1))
            .collect();
        assert_eq!(whites.len(), 9, "{t:?}");
        assert!(whites
            .iter()
            .all(|&(x, y)| (18..21).contains(&x) && (18..21).contains(&y)));
    }
}

/// A constant frame resizes to the same constant, shrinking or
/// enlarging, by whole and fractional factors, with either method.
#[test]
fn resize_of_a_constant_frame_is_constant() {
    for level in [0u8, 1, 77, 254, 255] {
        let frame = Frame::from_pixel(30, 20, image::Luma([level]));
        for size in [[15, 10], [7, 13], [64, 41], [30, 20], [1, 1], [31, 5]] {
            for method in [ResizeMethod::Area, ResizeMethod::Bilinear] {
                let out = resize(&frame, size, method);
                assert_eq!(out.dimensions(), (size[0], size[1]));
                assert!(out.pixels().all(|p| p[0] == level), "{size:?} {method:?}");
            }
        }
    }
}

/// A crop box outside the frame is refused when the stage is laid out,
/// an empty one when the settings are checked, and a frame of another
/// size when it is applied.
#[test]
fn crop_bounds_and_frame_sizes_are_refused() {
    let p = |crop| PreprocessParams {
        crop: Some(crop),
        ..PreprocessParams::default()
    };
    let checked = p([10, 10, 50, 40]).check().expect("valid");
    assert_eq!(
        checked.stage(49, 60),
        Err(VisionError::Crop {
            crop: [10, 10, 50, 40],
            width: 49,
            height: 60
        })
    );
    assert!(checked.stage(50, 40).is_ok());
    assert!(p([10, 10, 10, 40]).check().is_err());
    assert!(p([10, 41, 50, 40]).check().is_err());
    let s = checked.stage(64, 48).expect("fits");
    assert_eq!(s.output_size(), [40, 30]);
    assert_eq!(
        s.apply(&white(64, 49)),
        Err(VisionError::FrameSize {
            expected: [64, 48],
            found: [64, 49]
        })
    );
}

/// The steps run in order: the crop moves the mask's frame, the mask
/// holds through a threshold that would whiten flat ground, the resize
/// comes last.
#[test]
fn steps_run_in_order() {
    let p = PreprocessParams {
        crop: Some([4, 2, 24, 22]),
        mask: Some(MaskCircle {
            centre: [10.0, 10.0],
            radius: 4.0,
        }),
        threshold: Some(Threshold::AdaptiveMean { block: 3, c: 1.0 }),
        resize: Some(Resize {
            size: [10, 10],
            method: ResizeMethod::Area,
        }),
        ..PreprocessParams::default()
    };
    let s = stage(p, 30, 25);
    let out = s.apply(&white(30, 25)).expect("apply");
    assert_eq!(out.dimensions(), (10, 10));
    // The 20 x 20 crop halved: the circle of radius 4 at (10, 10) becomes
    // one of radius 2 at (4.75, 4.75); corners stay black.
    assert_eq!(out.get_pixel(0, 0)[0], 0);
    assert_eq!(out.get_pixel(9, 9)[0], 0);
    assert_eq!(out.get_pixel(5, 5)[0], 255);
    assert!(s.keeps(10, 10) && !s.keeps(0, 0));
}

#[test]
fn settings_read_from_toml_and_refuse_unknown_keys() {
    let text = "crop = [190, 132, 446, 388]\nmedian_blur = 5\n\
                mask = { centre = [128.0, 128.0], radius = 120.0 }\n\
                threshold = { kind = \"adaptive_gaussian\", block = 61, c = -5.0 }\n\
                resize = { size = [128, 128] }\n";
    let p: PreprocessParams = toml::from_str(text).expect("parses");
    assert_eq!(
        p.threshold,
        Some(Threshold::AdaptiveGaussian { block: 61, c: -5.0 })
    );
    assert_eq!(p.resize.map(|r| r.method), Some(ResizeMethod::Area));
    let back: PreprocessParams =
        toml::from_str(&toml::to_string(&p).expect("writes")).expect("reads");
    assert_eq!(back, p);
    for bad in [
        format!("{text}invert = true\n"),
        "threshold = { kind = \"global\", level = 10, c = 1.0 }\n".to_string(),
        "mask = { centre = [1.0, 1.0], radius = 2.0, soft = 1 }\n".to_string(),
    ] {
        assert!(toml::from_str::<PreprocessParams>(&bad).is_err(), "{bad}");
    }
    for bad in [
        "median_blur = 4\n",
        "threshold = { kind = \"adaptive_mean\", block = 1, c = -5.0 }\n",
        "mask = { centre = [1.0, 1.0], radius = 0.0 }\n",
        "resize = { size = [0, 10] }\n",
    ] {
        let p: PreprocessParams = toml::from_str(bad).expect("parses");
        assert!(p.check().is_err(), "{bad}");
    }
}
