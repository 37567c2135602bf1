//! Exif kept with a photo whose pixels are stored upright.

use image::metadata::Orientation;

/// Makes a camera's Exif say what qcs stores: its orientation set to upright (the pixels
/// have been turned), and, if they were turned, its embedded thumbnail (IFD1, drawn as the
/// camera held it) unlinked, lest a viewer show it sideways. Exif that does not parse is
/// left as it is.
pub fn upright(exif: &mut [u8]) {
    let turned =
        Orientation::remove_from_exif_chunk(exif).is_some_and(|o| o != Orientation::NoTransforms);
    if turned {
        unlink_thumbnail(exif);
    }
}

/// Sets the first IFD's link to the next (the thumbnail's IFD1) to 0, the TIFF end of the
/// chain. `None` if the block is not TIFF-shaped that far.
fn unlink_thumbnail(exif: &mut [u8]) -> Option<()> {
    let big = match exif.get(..4)? {
        b"MM\0*" => true,
        b"II*\0" => false,
        _ => return None,
    };
    let read = |b: &[u8], at: usize, n: usize| -> Option<usize> {
        let bytes = b.get(at..at.checked_add(n)?)?;
        let fold = |v: usize, &x: &u8| v << 8 | x as usize;
        Some(match big {
            true => bytes.iter().fold(0, fold),
            false => bytes.iter().rev().fold(0, fold),
        })
    };
    let ifd0 = read(exif, 4, 4)?;
    let entries = read(exif, ifd0, 2)?;
    let link = ifd0.checked_add(2 + 12 * entries)?;
    exif.get_mut(link..link.checked_add(4)?)?.fill(0);
    Some(())
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A TIFF block in either byte order: one IFD of one entry, Orientation = `o`, linked to
    /// an IFD1 at byte 26 of no entries.
    fn exif(big: bool, o: u8) -> Vec<u8> {
        let mut e: Vec<u8> = match big {
            true => vec![
                b'M', b'M', 0, 42, 0, 0, 0, 8, 0, 1, 0x01, 0x12, 0, 3, 0, 0, 0, 1, 0, o, 0, 0,
            ],
            false => vec![
                b'I', b'I', 42, 0, 8, 0, 0, 0, 1, 0, 0x12, 0x01, 3, 0, 1, 0, 0, 0, o, 0, 0, 0,
            ],
        };
        e.extend_from_slice(if big { &[0, 0, 0, 26] } else { &[26, 0, 0, 0] });
        e.extend_from_slice(&[0; 6]);
        e
    }

    #[test]
    fn a_turned_photo_s_exif_says_upright_and_loses_its_thumbnail() {
        for big in [true, false] {
            let mut e = exif(big, 6);
            upright(&mut e);
            assert_eq!(
                Orientation::from_exif_chunk(&e),
                Some(Orientation::NoTransforms)
            );
            let mut want = exif(big, 1);
            want[22..26].fill(0);
            assert_eq!(e, want, "big-endian {big}");
        }
    }

    #[test]
    fn an_upright_photo_s_exif_is_kept_as_it_is() {
        for big in [true, false] {
            let mut e = exif(big, 1);
            upright(&mut e);
            assert_eq!(e, exif(big, 1));
        }
        let mut garbage = b"MM\0*\xff\xff\xff\xff".to_vec();
        upright(&mut garbage);
        assert_eq!(garbage, b"MM\0*\xff\xff\xff\xff");
        let mut cut = exif(true, 6)[..20].to_vec();
        upright(&mut cut);
        assert_eq!(cut, exif(true, 6)[..20]);
    }
}
