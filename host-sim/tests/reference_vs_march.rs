//! The exact reference against a brute-force march: tiny fixed steps along
//! each ray, then bisection, over a rough random terrain. Both must agree on
//! hit or miss and on where the hit is.

use terracast_sim::reference::Reference;
use terracast_sim::scene::Scene;

fn lcg(state: &mut u64) -> f64 {
    *state = state
        .wrapping_mul(6364136223846793005)
        .wrapping_add(1442695040888963407);
    (*state >> 11) as f64 / (1u64 << 53) as f64
}

/// First t with the ray at or below the surface, found with steps of `step`
/// (in t) and refined by bisection.
fn march(scene: &Scene, o: [f64; 3], d: [f64; 3], step: f64) -> Option<f64> {
    let ext = [f64::from(scene.width - 1), f64::from(scene.depth - 1)];
    let inside = |t: f64| {
        let (x, y) = (o[0] + t * d[0], o[1] + t * d[1]);
        (0.0..=ext[0]).contains(&x) && (0.0..=ext[1]).contains(&y)
    };
    let below = |t: f64| o[2] + t * d[2] <= scene.height_at(o[0] + t * d[0], o[1] + t * d[1]);
    let mut t = 0.0;
    let mut was_inside = false;
    while t < 200.0 {
        if inside(t) {
            if below(t) {
                if !was_inside {
                    return Some(t);
                }
                let (mut lo, mut hi) = (t - step, t);
                for _ in 0..60 {
                    let mid = 0.5 * (lo + hi);
                    if below(mid) {
                        hi = mid
                    } else {
                        lo = mid
                    }
                }
                return Some(hi);
            }
            was_inside = true;
        } else if was_inside {
            return None;
        }
        t += step;
    }
    None
}

#[test]
fn reference_agrees_with_a_fine_march() {
    let mut rng = 7u64;
    let side = 24u32;
    let heights: Vec<f32> = (0..side * side)
        .map(|_| (lcg(&mut rng) * 12.0) as f32)
        .collect();
    let scene = Scene::new(side, side, heights, vec![[0; 3]; (side * side) as usize]).unwrap();
    let reference = Reference::new(&scene);
    let (mut agree, mut total, mut worst) = (0, 0, 0.0f64);
    for _ in 0..400 {
        let o = [
            lcg(&mut rng) * 30.0 - 3.0,
            lcg(&mut rng) * 30.0 - 3.0,
            8.0 + lcg(&mut rng) * 10.0,
        ];
        let a = lcg(&mut rng) * std::f64::consts::TAU;
        let down = -0.05 - lcg(&mut rng) * 0.8;
        let d = [a.cos(), a.sin(), down];
        let exact = reference.intersect(o, d, &mut 0).map(|h| h.t);
        let brute = march(&scene, o, d, 1e-4);
        total += 1;
        match (exact, brute) {
            (Some(e), Some(b)) => {
                worst = f64::max(worst, (e - b).abs());
                agree += 1;
            }
            (None, None) => agree += 1,
            _ => {}
        }
    }
    println!("{agree}/{total} rays agree on hit or miss; worst |Δt| {worst:.2e}");
    assert!(
        agree >= total * 995 / 1000,
        "only {agree} of {total} rays agree"
    );
    assert!(worst < 2e-3, "hit positions differ by {worst}");
}
