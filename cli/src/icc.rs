//! ICC colour profiles: whether one draws sRGB's colours (which a file without one means).
//!
//! Profiles are read with `moxcms`, the colour management crate `image` itself uses.

use moxcms::{ColorProfile, DataColorSpace, Layout, TransformOptions};

/// Whether an ICC profile draws the colours sRGB draws: an RGB profile whose transform to sRGB
/// moves no colour of an 9×9×9 grid of 8-bit RGB by more than 2 levels. Storing such a profile
/// would only repeat what a file without one means. Judged by what the profile does, not by
/// its name: "sRGB2014" or a camera's own sRGB profile count, a profile merely named "sRGB" does
/// not. A profile that does not parse is not sRGB.
pub fn is_srgb(icc: &[u8]) -> bool {
    let Ok(profile) = ColorProfile::new_from_slice(icc) else {
        return false;
    };
    if profile.color_space != DataColorSpace::Rgb {
        return false;
    }
    let to_srgb = profile.create_transform_8bit(
        Layout::Rgb,
        &ColorProfile::new_srgb(),
        Layout::Rgb,
        TransformOptions::default(),
    );
    let Ok(to_srgb) = to_srgb else {
        return false;
    };
    let grid: Vec<u8> = (0..9 * 9 * 9u32)
        .flat_map(|i| [i / 81, i / 9 % 9, i % 9].map(|v| (v * 255 / 8) as u8))
        .collect();
    let mut out = vec![0; grid.len()];
    to_srgb.transform(&grid, &mut out).is_ok()
        && grid.iter().zip(&out).all(|(a, b)| a.abs_diff(*b) <= 2)
}

#[cfg(test)]
mod tests {
    use super::is_srgb;
    use moxcms::ColorProfile;

    fn bytes(p: ColorProfile) -> Vec<u8> {
        p.encode().expect("moxcms writes its own profiles")
    }

    #[test]
    fn srgb_profiles_are_recognised_by_their_colours() {
        let srgb = bytes(ColorProfile::new_srgb());
        assert!(is_srgb(&srgb));
        assert!(!is_srgb(&bytes(ColorProfile::new_display_p3())));
        assert!(!is_srgb(&bytes(ColorProfile::new_adobe_rgb())));
        assert!(!is_srgb(&bytes(ColorProfile::new_bt2020())));
        assert!(!is_srgb(&bytes(ColorProfile::new_gray_with_gamma(2.2))));
        // Cut or garbled profiles are not sRGB (and do not panic).
        for n in 0..srgb.len() {
            let _ = is_srgb(&srgb[..n]);
        }
        assert!(!is_srgb(&srgb[..srgb.len() / 2]));
        let mut flipped = srgb.clone();
        for i in (0..flipped.len()).step_by(7) {
            flipped[i] ^= 0x5A;
            let _ = is_srgb(&flipped);
        }
        assert!(!is_srgb(b"not a profile"));
    }
}
