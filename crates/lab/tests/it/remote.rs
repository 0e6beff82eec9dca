//! The worker's side of a remote executor (issue 24): evaluations found by
//! name, their context and configuration checked, and a Ray executor that
//! cannot start refused as bad input. (The round trip through a real Ray
//! cluster is crates/py/tests/test_ray.py.)
use tactrace_lab::remote::{evaluate, prepare, Exec, RayExecutor, RaySettings, RemoteError};
use tactrace_lab::search::PoseTrial;
use tactrace_lab::LabError;
use tactrace_optim::{Evaluation, Executor};

fn remote(e: LabError) -> RemoteError {
    match e {
        LabError::Remote(r) => r,
        other => panic!("expected a remote error, got {other}"),
    }
}

#[test]
fn a_worker_refuses_an_unknown_evaluation_and_a_bad_context() {
    let e = evaluate("no.such.evaluation", "{}", "{}").unwrap_err();
    assert!(e.is_bad_input());
    assert!(
        matches!(remote(e), RemoteError::UnknownEvaluation { name } if name == "no.such.evaluation")
    );
    for name in [
        PoseTrial::NAME,
        tactrace_lab::transfer_fit::TransferTrial::NAME,
        tactrace_lab::tune::TuneTrial::NAME,
        tactrace_lab::tune::HeldOutTrial::NAME,
    ] {
        let e = evaluate(name, "{\"not\": \"a context\"}", "{}").unwrap_err();
        assert!(e.is_bad_input(), "{name}: {e}");
        match remote(e) {
            RemoteError::Json {
                what, evaluation, ..
            } => {
                assert_eq!((what, evaluation.as_str()), ("context", name))
            }
            other => panic!("{name}: {other}"),
        }
    }
    // A search whose training data is not where the context says.
    let context =
        r#"{"train": "/no/such/dataset", "data_sha256": "x", "val_fraction": 0.25, "seed": 0}"#;
    let e = evaluate(PoseTrial::NAME, context, "{}").unwrap_err();
    assert!(e.is_bad_input(), "{e}");
}

#[test]
fn a_ray_executor_without_its_interpreter_is_bad_input() {
    let ray = RayExecutor::new(RaySettings {
        address: "127.0.0.1:1".into(),
        python: "/no/such/python3".into(),
        cpus_per_task: 1,
    });
    let e = LabError::from(ray.connect().unwrap_err());
    assert!(e.is_bad_input());
    let text = tactrace_lab::error::error_chain(&e);
    assert!(
        text.contains("/no/such/python3") && text.contains("TACTRACE_PYTHON"),
        "{text}"
    );
    // Through the executor interface the same error comes back, typed.
    let exec = Exec::Ray(ray);
    struct Twice;
    impl Evaluation for Twice {
        const NAME: &'static str = "twice";
        type Config = f64;
        type Score = f64;
        type Error = LabError;
        fn evaluate(&self, x: &f64) -> Result<f64, LabError> {
            Ok(2.0 * x)
        }
        fn context(&self) -> Option<String> {
            Some("{}".into())
        }
    }
    let e = LabError::from(exec.run(&Twice, &[1.0]).unwrap_err());
    assert!(
        matches!(e, LabError::Remote(RemoteError::PythonNotFound { .. })),
        "{e}"
    );
    assert_eq!(
        Exec::Local.run(&Twice, &[1.0, 2.5]).unwrap(),
        vec![2.0, 5.0]
    );
}

#[test]
fn a_worker_prepares_only_what_it_could_evaluate() {
    let e = prepare("no.such.evaluation", "{}").unwrap_err();
    assert!(e.is_bad_input());
    assert!(matches!(remote(e), RemoteError::UnknownEvaluation { .. }));
    for name in [
        PoseTrial::NAME,
        tactrace_lab::transfer_fit::TransferTrial::NAME,
        tactrace_lab::tune::TuneTrial::NAME,
        tactrace_lab::tune::HeldOutTrial::NAME,
    ] {
        let e = prepare(name, "[1, 2]").unwrap_err();
        assert!(e.is_bad_input(), "{name}: {e}");
        assert!(
            matches!(remote(e), RemoteError::Json { what: "context", ref evaluation, .. } if evaluation == name)
        );
    }
    let context =
        r#"{"train": "/no/such/dataset", "data_sha256": "x", "val_fraction": 0.25, "seed": 0}"#;
    let e = prepare(PoseTrial::NAME, context).unwrap_err();
    assert!(e.is_bad_input(), "{e}");
}
