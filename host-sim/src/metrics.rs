//! Image and depth comparisons against the reference.

use terracast::Rgb;

/// Peak signal-to-noise ratio over all RGB channels, in dB (infinite for
/// identical images).
pub fn psnr(test: &[Rgb], reference: &[Rgb]) -> f64 {
    let n = test.len().min(reference.len()) * 3;
    let sum: f64 = test
        .iter()
        .zip(reference)
        .flat_map(|(a, b)| (0..3).map(move |k| (f64::from(a[k]) - f64::from(b[k])).powi(2)))
        .sum();
    if sum == 0.0 {
        return f64::INFINITY;
    }
    10.0 * (255.0f64 * 255.0 / (sum / n as f64)).log10()
}

/// Structural similarity of the two images' luma (Rec. 601), mean SSIM
/// over 8 × 8 windows (image-compare's `MSSIMSimple`): 1 for identical
/// images. `None` when the slices do not match `width` × `height`.
pub fn ssim(test: &[Rgb], reference: &[Rgb], width: u32, height: u32) -> Option<f64> {
    let luma = |pixels: &[Rgb]| {
        let raw: Vec<u8> = pixels.iter().flatten().copied().collect();
        image::RgbImage::from_raw(width, height, raw).map(|rgb| image::imageops::grayscale(&rgb))
    };
    let (a, b) = (luma(test)?, luma(reference)?);
    image_compare::gray_similarity_structure(&image_compare::Algorithm::MSSIMSimple, &a, &b)
        .ok()
        .map(|similarity| similarity.score)
}

/// Mean absolute difference per channel (0–255) between two images: the
/// frame-to-frame change of a flight.
pub fn mean_abs_difference(a: &[Rgb], b: &[Rgb]) -> f64 {
    let n = a.len().min(b.len()) * 3;
    let sum: u64 = a
        .iter()
        .zip(b)
        .flat_map(|(x, y)| (0..3).map(move |k| u64::from(x[k].abs_diff(y[k]))))
        .sum();
    sum as f64 / n.max(1) as f64
}

/// [`mean_abs_difference`] of each image row (`width` pixels a row): where
/// in the image the change is.
pub fn row_mean_abs_difference(a: &[Rgb], b: &[Rgb], width: usize) -> Vec<f64> {
    a.chunks(width.max(1))
        .zip(b.chunks(width.max(1)))
        .map(|(x, y)| mean_abs_difference(x, y))
        .collect()
}

/// Fraction of pixels on which both depth maps agree about sky (infinite)
/// versus terrain (finite).
pub fn sky_agreement(test: &[f32], reference: &[f32]) -> f64 {
    let agree = test
        .iter()
        .zip(reference)
        .filter(|(a, b)| a.is_finite() == b.is_finite())
        .count();
    agree as f64 / test.len().max(1) as f64
}

/// Median of |test − reference| / reference over pixels where both see
/// terrain; `None` if there are none.
pub fn median_relative_depth_error(test: &[f32], reference: &[f32]) -> Option<f64> {
    relative_depth_error_quantile(test, reference, 0.5)
}

/// The `q` quantile (0 to 1; 0.95 for the 95th percentile) of
/// |test − reference| / reference over pixels where both see terrain;
/// `None` if there are none.
pub fn relative_depth_error_quantile(test: &[f32], reference: &[f32], q: f64) -> Option<f64> {
    let mut errors: Vec<f64> = test
        .iter()
        .zip(reference)
        .filter(|(a, b)| a.is_finite() && b.is_finite() && **b > 0.0)
        .map(|(a, b)| (f64::from(*a) - f64::from(*b)).abs() / f64::from(*b))
        .collect();
    if errors.is_empty() {
        return None;
    }
    let at = ((errors.len() - 1) as f64 * q.clamp(0.0, 1.0)).round() as usize;
    let (_, value, _) = errors.select_nth_unstable_by(at, f64::total_cmp);
    Some(*value)
}

/// Number of pixels whose colors differ.
pub fn differing_pixels(a: &[Rgb], b: &[Rgb]) -> usize {
    a.iter().zip(b).filter(|(x, y)| x != y).count()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn ssim_is_one_for_equal_images_and_falls_with_noise() {
        let (w, h) = (32u32, 24u32);
        let image: Vec<Rgb> = (0..w * h)
            .map(|i| [(i * 7 % 256) as u8, (i / w * 10) as u8, 128])
            .collect();
        assert!((ssim(&image, &image, w, h).unwrap() - 1.0).abs() < 1e-9);
        let mut state = 1u32;
        let noisy: Vec<Rgb> = image
            .iter()
            .map(|p| {
                state = state.wrapping_mul(1_103_515_245).wrapping_add(12345);
                p.map(|v| v.saturating_add((state >> 27) as u8))
            })
            .collect();
        let s = ssim(&noisy, &image, w, h).unwrap();
        assert!(s < 0.99 && s > 0.0, "{s}");
        assert_eq!(ssim(&image, &image, w, h + 1), None);
    }

    #[test]
    fn psnr_of_known_error() {
        let a = vec![[10u8, 10, 10]; 4];
        let b = vec![[11u8, 10, 10]; 4];
        // MSE = 1/3 per channel.
        let expect = 10.0 * (255.0f64 * 255.0 * 3.0).log10();
        assert!((psnr(&a, &b) - expect).abs() < 1e-9);
        assert!(psnr(&a, &a).is_infinite());
    }

    #[test]
    fn depth_metrics() {
        let r = [10.0, 20.0, f32::INFINITY, 40.0];
        let t = [11.0, 20.0, f32::INFINITY, f32::INFINITY];
        assert_eq!(sky_agreement(&t, &r), 0.75);
        assert_eq!(median_relative_depth_error(&t, &r), Some(0.1));
        let spread: Vec<f32> = (0..101).map(|i| 100.0 + i as f32).collect();
        let exact = vec![100.0f32; 101];
        assert_eq!(
            relative_depth_error_quantile(&spread, &exact, 0.95),
            Some(0.95)
        );
        assert_eq!(
            relative_depth_error_quantile(&spread, &exact, 0.0),
            Some(0.0)
        );
        assert_eq!(
            relative_depth_error_quantile(&[f32::INFINITY], &[1.0], 0.5),
            None
        );
    }
}
