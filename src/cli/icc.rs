//! ICC colour profiles: whether one describes sRGB (which a file without one means).

/// Whether an ICC profile describes sRGB (an RGB profile whose description names it, as
/// "sRGB IEC61966-2.1" or "sRGB built-in" do): storing it would only repeat what a file
/// without a profile means. Reads the `desc` tag, ICC v2 (`desc`) or v4 (`mluc`, UTF-16).
pub fn is_srgb(icc: &[u8]) -> bool {
    let u32_at = |at: usize| -> Option<usize> {
        let b = icc.get(at..at.checked_add(4)?)?;
        Some(u32::from_be_bytes([b[0], b[1], b[2], b[3]]) as usize)
    };
    let desc = || -> Option<String> {
        if icc.get(16..20)? != b"RGB " {
            return None;
        }
        let tags = u32_at(128)?;
        let (at, len) = (0..tags.min(1024)).find_map(|i| {
            let e = 132 + 12 * i;
            if icc.get(e..e + 4)? != b"desc" {
                return None;
            }
            Some((u32_at(e + 4)?, u32_at(e + 8)?))
        })?;
        let tag = icc.get(at..at.checked_add(len)?)?;
        match tag.get(..4)? {
            b"desc" => {
                let n = u32_at(at + 8)?;
                Some(String::from_utf8_lossy(tag.get(12..12usize.checked_add(n)?)?).into())
            }
            b"mluc" => {
                // The first record: its length and offset from the tag's start.
                let (n, off) = (u32_at(at + 20)?, u32_at(at + 24)?);
                let text = tag.get(off..off.checked_add(n)?)?;
                let units = text
                    .chunks_exact(2)
                    .map(|c| u16::from_be_bytes([c[0], c[1]]));
                Some(
                    char::decode_utf16(units)
                        .map(|c| c.unwrap_or('?'))
                        .collect(),
                )
            }
            _ => None,
        }
    };
    desc().is_some_and(|d| d.contains("sRGB"))
}

#[cfg(test)]
mod tests {
    use super::is_srgb;

    /// A minimal RGB profile whose only tag is `desc`, holding `tag`.
    fn profile(tag: &[u8]) -> Vec<u8> {
        let mut p = vec![0u8; 128];
        p[16..20].copy_from_slice(b"RGB ");
        p.extend_from_slice(&1u32.to_be_bytes());
        p.extend_from_slice(b"desc");
        p.extend_from_slice(&144u32.to_be_bytes());
        p.extend_from_slice(&(tag.len() as u32).to_be_bytes());
        p.extend_from_slice(tag);
        p
    }

    /// A v2 `desc` tag.
    fn v2(text: &str) -> Vec<u8> {
        let mut t = b"desc\0\0\0\0".to_vec();
        t.extend_from_slice(&(text.len() as u32 + 1).to_be_bytes());
        t.extend_from_slice(text.as_bytes());
        t.push(0);
        profile(&t)
    }

    /// A v4 `mluc` tag with one record.
    fn v4(text: &str) -> Vec<u8> {
        let utf16: Vec<u8> = text.encode_utf16().flat_map(u16::to_be_bytes).collect();
        let mut t = b"mluc\0\0\0\0".to_vec();
        for n in [1u32, 12] {
            t.extend_from_slice(&n.to_be_bytes());
        }
        t.extend_from_slice(b"enUS");
        t.extend_from_slice(&(utf16.len() as u32).to_be_bytes());
        t.extend_from_slice(&28u32.to_be_bytes());
        t.extend_from_slice(&utf16);
        profile(&t)
    }

    #[test]
    fn srgb_profiles_are_recognised_by_their_description() {
        assert!(is_srgb(&v2("sRGB IEC61966-2.1")));
        assert!(is_srgb(&v4("sRGB built-in")));
        assert!(!is_srgb(&v2("Display P3")));
        assert!(!is_srgb(&v4("Adobe RGB (1998)")));
        // A grey profile is not sRGB whatever it says.
        let mut grey = v2("sRGB");
        grey[16..20].copy_from_slice(b"GRAY");
        assert!(!is_srgb(&grey));
        // Cut or garbled profiles are not sRGB (and do not panic).
        let whole = v4("sRGB built-in");
        for n in 0..whole.len() {
            assert!(!is_srgb(&whole[..n]), "cut at {n}");
        }
        let mut far = v2("sRGB");
        far[136..140].copy_from_slice(&u32::MAX.to_be_bytes());
        assert!(!is_srgb(&far));
        assert!(!is_srgb(b"not a profile"));
    }
}
