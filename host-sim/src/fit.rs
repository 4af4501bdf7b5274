//! Least-squares fits of prices: what each counted thing a frame does
//! costs, from frames' counts and their measured cost (the board's
//! instructions, this machine's time).

/// The least-squares weights `w` of `y ≈ Σ wᵢ·xᵢ` (no constant term)
/// over `rows`, from the normal equations by Gaussian elimination with
/// partial pivoting; `None` where the columns do not tell the weights
/// apart (fewer rows than weights, or a column a blend of the others).
pub fn least_squares_through_origin<const N: usize>(rows: &[([f64; N], f64)]) -> Option<[f64; N]> {
    least_squares_over(rows, [true; N]).ok()
}

/// [`least_squares_through_origin`] with no weight below 0: a column whose
/// weight comes out negative (a price that noise or a near-blend of the
/// other columns pushed below zero) is held at 0, the most negative first,
/// and the others fitted again (the active-set way). A column the others
/// already explain (all zero, or a blend of them: frames that never tell
/// its count apart) is held at 0 too. `None` where no column is left.
pub fn non_negative_least_squares<const N: usize>(rows: &[([f64; N], f64)]) -> Option<[f64; N]> {
    let mut kept = [true; N];
    loop {
        let weights = match least_squares_over(rows, kept) {
            Ok(weights) => weights,
            Err(Some(blend)) => {
                kept[blend] = false;
                continue;
            }
            Err(None) => return None,
        };
        let most_negative = (0..N)
            .filter(|&i| kept[i] && weights[i] < 0.0)
            .min_by(|&a, &b| weights[a].total_cmp(&weights[b]));
        match most_negative {
            None => return Some(weights),
            Some(i) => kept[i] = false,
        }
    }
}

/// The least-squares weights of the `kept` columns; the others are 0.
/// `Err(Some(c))` where column `c` is a blend of the ones before it (the
/// rows do not tell its weight apart), `Err(None)` where no column is kept.
fn least_squares_over<const N: usize>(
    rows: &[([f64; N], f64)],
    kept: [bool; N],
) -> Result<[f64; N], Option<usize>> {
    let columns: Vec<usize> = (0..N).filter(|&i| kept[i]).collect();
    let n = columns.len();
    if n == 0 {
        return Err(None);
    }
    // [XᵀX | Xᵀy], row by row.
    let mut system = vec![vec![0.0f64; n]; n];
    let mut right = vec![0.0f64; n];
    for (x, y) in rows {
        for (i, &ci) in columns.iter().enumerate() {
            for (j, &cj) in columns.iter().enumerate() {
                system[i][j] += x[ci] * x[cj];
            }
            right[i] += x[ci] * y;
        }
    }
    let scale = system
        .iter()
        .enumerate()
        .map(|(i, row)| row[i])
        .fold(0.0f64, f64::max);
    for column in 0..n {
        let pivot = (column..n)
            .max_by(|&a, &b| system[a][column].abs().total_cmp(&system[b][column].abs()))
            .ok_or(None)?;
        if system[pivot][column].abs() <= 1e-12 * scale.max(1e-300) {
            return Err(Some(columns[column]));
        }
        system.swap(column, pivot);
        right.swap(column, pivot);
        let (pivot_row, pivot_right) = (system[column].clone(), right[column]);
        for (row, right) in system.iter_mut().zip(&mut right).skip(column + 1) {
            let factor = row[column] / pivot_row[column];
            for (value, pivot) in row.iter_mut().zip(&pivot_row).skip(column) {
                *value -= factor * pivot;
            }
            *right -= factor * pivot_right;
        }
    }
    let mut solved = vec![0.0f64; n];
    for row in (0..n).rev() {
        let known: f64 = (row + 1..n).map(|j| system[row][j] * solved[j]).sum();
        solved[row] = (right[row] - known) / system[row][row];
    }
    let mut weights = [0.0f64; N];
    for (&c, w) in columns.iter().zip(solved) {
        weights[c] = w;
    }
    Ok(weights)
}

/// The least-squares fit `y = a + b·x₀ + c·x₁` through `points`, as
/// `[a, b, c]`. Where `x₀` does not vary apart from `x₁` (nothing tells the
/// two apart), `b` is 0 and `c` is the least-squares line's slope.
pub fn least_squares(points: &[([f64; 2], f64)]) -> [f64; 3] {
    let n = points.len().max(1) as f64;
    let (m0, m1, my) = points.iter().fold((0.0, 0.0, 0.0), |(a, b, y), p| {
        (a + p.0[0] / n, b + p.0[1] / n, y + p.1 / n)
    });
    // Sums of products about the means: the normal equations of b and c.
    let sum = |f: &dyn Fn(f64, f64, f64) -> f64| -> f64 {
        points
            .iter()
            .map(|p| f(p.0[0] - m0, p.0[1] - m1, p.1 - my))
            .sum()
    };
    let (s00, s01, s11) = (
        sum(&|a, _, _| a * a),
        sum(&|a, b, _| a * b),
        sum(&|_, b, _| b * b),
    );
    let (s0y, s1y) = (sum(&|a, _, y| a * y), sum(&|_, b, y| b * y));
    let det = s00 * s11 - s01 * s01;
    let (b, c) = if det.abs() > 1e-9 * (s00 * s11).max(1e-12) {
        ((s0y * s11 - s1y * s01) / det, (s1y * s00 - s0y * s01) / det)
    } else {
        (0.0, s1y / s11.max(1e-12))
    };
    [my - b * m0 - c * m1, b, c]
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_cost_fit_is_the_least_squares_plane() {
        let close =
            |got: [f64; 3], want: [f64; 3]| got.iter().zip(want).all(|(g, w)| (g - w).abs() < 1e-9);
        // Exactly on y = 1 + 2·x₀ + 3·x₁.
        let exact: Vec<_> = [[0.0, 0.0], [1.0, 0.0], [0.0, 1.0], [2.0, 5.0]]
            .into_iter()
            .map(|x| (x, 1.0 + 2.0 * x[0] + 3.0 * x[1]))
            .collect();
        let fit = least_squares(&exact);
        assert!(close(fit, [1.0, 2.0, 3.0]), "{fit:?}");
        // Off any plane by ±0.5 in a pattern the regressors cannot follow.
        let noisy = [
            ([0.0, 0.0], 1.0),
            ([1.0, 0.0], 0.0),
            ([0.0, 1.0], 0.0),
            ([1.0, 1.0], 1.0),
        ];
        let fit = least_squares(&noisy);
        assert!(close(fit, [0.5, 0.0, 0.0]), "{fit:?}");
        // x₀ constant: nothing tells it from the intercept, so it gets 0.
        let line = [([2.0, 1.0], 3.0), ([2.0, 2.0], 5.0), ([2.0, 4.0], 9.0)];
        let fit = least_squares(&line);
        assert!(close(fit, [1.0, 0.0, 2.0]), "{fit:?}");
    }

    #[test]
    fn prices_through_the_origin_are_the_least_squares_ones() {
        let close =
            |got: [f64; 2], want: [f64; 2]| got.iter().zip(want).all(|(g, w)| (g - w).abs() < 1e-9);
        // Exactly on y = 2·x₀ + 5·x₁.
        let exact: Vec<_> = [[1.0, 0.0], [1.0, 1.0], [2.0, 3.0]]
            .into_iter()
            .map(|x| (x, 2.0 * x[0] + 5.0 * x[1]))
            .collect();
        let fit = least_squares_through_origin(&exact).unwrap();
        assert!(close(fit, [2.0, 5.0]), "{fit:?}");
        // y = 1 and y = 3 at x = 1: the weight is their mean.
        let fit = least_squares_through_origin(&[([1.0], 1.0), ([1.0], 3.0)]).unwrap();
        assert!((fit[0] - 2.0).abs() < 1e-12, "{fit:?}");
        // One column twice the other: nothing tells them apart.
        let twins = [([1.0, 2.0], 3.0), ([2.0, 4.0], 5.0), ([3.0, 6.0], 8.0)];
        assert_eq!(least_squares_through_origin(&twins), None);
        assert_eq!(least_squares_through_origin::<2>(&[]), None);
    }

    #[test]
    fn a_weight_that_would_go_negative_is_held_at_zero() {
        // y = 3·x₀ − 0.5·x₁ exactly: the plain fit finds the negative
        // weight; the non-negative one holds it at 0 and refits x₀ alone.
        let rows: Vec<_> = [[1.0, 1.0], [2.0, 1.0], [3.0, 4.0], [4.0, 2.0]]
            .into_iter()
            .map(|x| (x, 3.0 * x[0] - 0.5 * x[1]))
            .collect();
        let plain = least_squares_through_origin(&rows).unwrap();
        assert!((plain[1] + 0.5).abs() < 1e-9, "{plain:?}");
        let held = non_negative_least_squares(&rows).unwrap();
        assert_eq!(held[1], 0.0);
        let alone = least_squares_through_origin(
            &rows.iter().map(|(x, y)| ([x[0]], *y)).collect::<Vec<_>>(),
        )
        .unwrap();
        assert!(
            (held[0] - alone[0]).abs() < 1e-12,
            "{held:?} against {alone:?}"
        );
        // A column of zeros, and one the first explains twice over: held
        // at 0, where the plain fit cannot tell them apart.
        let blends: Vec<_> = rows
            .iter()
            .map(|(x, _)| ([x[0], 0.0, 2.0 * x[0], x[1]], 3.0 * x[0] + x[1]))
            .collect();
        assert_eq!(least_squares_through_origin(&blends), None);
        let fit = non_negative_least_squares(&blends).unwrap();
        assert!(
            (fit[0] - 3.0).abs() < 1e-9 && fit[1..3] == [0.0, 0.0] && (fit[3] - 1.0).abs() < 1e-9,
            "{fit:?}"
        );
        // Nothing negative: the same as the plain fit.
        let positive: Vec<_> = rows.iter().map(|(x, _)| (*x, x[0] + 2.0 * x[1])).collect();
        assert_eq!(
            non_negative_least_squares(&positive),
            least_squares_through_origin(&positive)
        );
    }
}
