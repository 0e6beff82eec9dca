//! CMA-ES against functions whose minimum is known.
use tactrace_optim::{Cmaes, CmaesConfig, OptimError};

fn minimise(f: impl Fn(&[f64]) -> f64, start: Vec<f64>, sigma: f64, generations: usize) -> Cmaes {
    let mut es = Cmaes::new(&CmaesConfig {
        start,
        sigma,
        population: None,
        seed: 7,
    })
    .unwrap();
    for _ in 0..generations {
        let xs = es.ask();
        let costs: Vec<f64> = xs.iter().map(|x| f(x)).collect();
        es.tell(&costs).unwrap();
    }
    es
}

fn sphere(x: &[f64]) -> f64 {
    x.iter().map(|v| v * v).sum()
}

#[test]
fn finds_the_minimum_of_a_shifted_sphere() {
    let f = |x: &[f64]| x.iter().map(|v| (v - 2.0).powi(2)).sum::<f64>();
    let es = minimise(f, vec![-3.0; 6], 1.0, 300);
    let (x, cost) = es.best().unwrap();
    assert!(cost < 1e-10, "{cost}");
    assert!(x.iter().all(|v| (v - 2.0).abs() < 1e-4), "{x:?}");
}

#[test]
fn learns_an_ill_conditioned_ellipsoid() {
    // Axis scales 1 .. 1000 (condition 10^6): only a learned covariance
    // gets there in few evaluations.
    let f = |x: &[f64]| {
        let n = x.len() as f64;
        x.iter()
            .enumerate()
            .map(|(i, v)| 1e6f64.powf(i as f64 / (n - 1.0)) * v * v)
            .sum::<f64>()
    };
    let es = minimise(f, vec![1.0; 5], 0.5, 600);
    assert!(es.best().unwrap().1 < 1e-8, "{}", es.best().unwrap().1);
}

#[test]
fn follows_the_rosenbrock_valley_to_its_end() {
    let f = |x: &[f64]| {
        x.windows(2)
            .map(|w| 100.0 * (w[1] - w[0] * w[0]).powi(2) + (1.0 - w[0]).powi(2))
            .sum::<f64>()
    };
    let es = minimise(f, vec![0.0; 4], 0.3, 1500);
    let (x, cost) = es.best().unwrap();
    assert!(cost < 1e-8, "{cost}");
    assert!(x.iter().all(|v| (v - 1.0).abs() < 1e-3), "{x:?}");
}

#[test]
fn the_same_seed_gives_the_same_search_and_nan_ranks_last() {
    let a = minimise(sphere, vec![1.0; 3], 0.5, 20);
    let b = minimise(sphere, vec![1.0; 3], 0.5, 20);
    assert_eq!(a.mean(), b.mean());
    let nan_first = |x: &[f64]| if x[0] > 0.0 { f64::NAN } else { sphere(x) };
    let c = minimise(nan_first, vec![-1.0; 3], 0.5, 50);
    assert!(c.best().unwrap().1.is_finite());
    assert!(c.best().unwrap().0[0] <= 0.0);
}

#[test]
fn bad_set_ups_and_generations_are_refused() {
    let cfg = |start: Vec<f64>, sigma: f64| CmaesConfig {
        start,
        sigma,
        population: None,
        seed: 1,
    };
    assert!(Cmaes::new(&cfg(vec![], 1.0)).is_err());
    assert!(Cmaes::new(&cfg(vec![f64::NAN], 1.0)).is_err());
    assert!(Cmaes::new(&cfg(vec![0.0], 0.0)).is_err());
    let mut es = Cmaes::new(&cfg(vec![0.0, 0.0], 1.0)).unwrap();
    let xs = es.ask();
    assert_eq!(xs.len(), es.population());
    assert_eq!(
        es.tell(&[1.0]),
        Err(OptimError::Generation {
            expected: xs.len(),
            got: 1
        })
    );
}

/// Issue 20: a population of 1e12 (`tune`'s `population`, `sim-fit
/// --population`) aborted on allocating its weights; it is refused with
/// the bound.
#[test]
fn a_huge_population_is_refused_with_the_bound() {
    let cfg = |population: usize| CmaesConfig {
        start: vec![0.0; 3],
        sigma: 1.0,
        population: Some(population),
        seed: 1,
    };
    let err = Cmaes::new(&cfg(1_000_000_000_000)).unwrap_err();
    assert!(err.to_string().contains("at most 100000"), "{err}");
    assert!(Cmaes::new(&cfg(100_000)).is_ok());
}
