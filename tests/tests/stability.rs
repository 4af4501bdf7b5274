//! The stability suite: every method at the conditions where terrain
//! renderers are known to fail. Nothing may panic or produce NaN; the
//! kernel must give a picture of the view at every condition; a method that
//! fails is reported as failing, with its figure.

use terracast_sim::stability::{run, table, Verdict};

#[test]
fn no_method_panics_the_kernel_passes_everything_and_failures_are_reported() {
    let outcomes = run((96, 72), |_, _| {}).unwrap();
    println!("{}", table(&outcomes));
    assert_eq!(outcomes.len(), 15 * 5);
    for o in &outcomes {
        assert_ne!(o.verdict, Verdict::Fails("panicked".into()), "{o:?}");
        assert_ne!(o.verdict, Verdict::Fails("NaN depth".into()), "{o:?}");
        if o.method == "kernel" {
            assert_eq!(o.verdict, Verdict::Passes, "{o:?}");
        }
    }
    // Voxel Space cannot pitch: looking straight down it draws another
    // picture, and the suite says so.
    let nadir = outcomes
        .iter()
        .find(|o| o.method == "voxelspace" && o.condition == "steep pitch 90°")
        .unwrap();
    assert!(matches!(nadir.verdict, Verdict::Fails(_)), "{nadir:?}");
    // Nor roll: its columns stay vertical. The march, the kernel and Qu's
    // volume roll.
    for o in outcomes.iter().filter(|o| o.condition.starts_with("roll")) {
        match o.method {
            "voxelspace" => assert_eq!(o.verdict, Verdict::Fails("cannot roll".into())),
            _ => assert_eq!(o.verdict, Verdict::Passes, "{o:?}"),
        }
    }
    // Qu's boundary array alone stops grazing rays a layer above the
    // ground: the suite says so.
    let grazing = outcomes
        .iter()
        .find(|o| o.method == "boundary" && o.condition == "grazing, pitch 2°")
        .unwrap();
    assert!(matches!(grazing.verdict, Verdict::Fails(_)), "{grazing:?}");
    assert!(table(&outcomes).contains("**fails**"));
}
