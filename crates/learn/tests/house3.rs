//! The learning crate's shared test data (`tests/support`) is the data the
//! tests made each for themselves before: seeded, shaped and valued as
//! they were.
mod support;

/// The same seed gives the same rows, another seed others; `n` rows of
/// `dim` values and two targets in their ranges, the values a smooth
/// function of the targets plus at most 0.2 of noise.
#[test]
fn issue21_correlated_rows_are_seeded_and_follow_their_targets() {
    let (x, y) = support::correlated_rows(50, 7, 3);
    assert_eq!((x.len(), y.len()), (350, 100));
    assert_eq!((x.clone(), y.clone()), support::correlated_rows(50, 7, 3));
    assert_ne!(y, support::correlated_rows(50, 7, 4).1);
    for (row, t) in x.chunks_exact(7).zip(y.chunks_exact(2)) {
        let (a, b) = (t[0], t[1]);
        assert!(
            (-5.0..5.0).contains(&a) && (-45.0..45.0).contains(&b),
            "{t:?}"
        );
        for (j, v) in row.iter().enumerate() {
            let phase = j as f32 * 0.37;
            let smooth = a * phase.sin() + 0.1 * b * phase.cos();
            assert!((v - smooth).abs() <= 0.2 + 1e-5, "{v} vs {smooth}");
        }
    }
}
