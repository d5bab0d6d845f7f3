//! Connected regions of one label in one slice.

/// One connected region (8-connectivity) of a label in a slice.
#[derive(Debug, Clone, PartialEq)]
pub struct Region {
    /// Label id.
    pub label: u16,
    /// Component id in the slice's component image.
    pub id: u32,
    /// Pixel count.
    pub area: u32,
    /// Centroid (pixel coordinates, pixel centres at integers).
    pub centroid: [f64; 2],
    /// Inclusive bounding box `[u0, v0, u1, v1]`.
    pub bbox: [u32; 4],
}

/// Component image and regions of one slice.
#[derive(Debug, Clone)]
pub struct SliceComponents {
    /// Component id per pixel (`u32::MAX` for background and ignored labels).
    pub image: Vec<u32>,
    /// Regions indexed by component id.
    pub regions: Vec<Region>,
}

/// Labels connected regions of every label for which `keep(label)` holds.
pub fn label_components(
    labels: &[u16],
    width: usize,
    height: usize,
    keep: impl Fn(u16) -> bool,
) -> SliceComponents {
    const NONE: u32 = u32::MAX;
    let mut image = vec![NONE; labels.len()];
    let mut regions = Vec::new();
    let mut stack: Vec<usize> = Vec::new();
    for start in 0..labels.len() {
        let lab = labels[start];
        if image[start] != NONE || !keep(lab) {
            continue;
        }
        let id = regions.len() as u32;
        image[start] = id;
        stack.push(start);
        let (mut n, mut su, mut sv) = (0u64, 0u64, 0u64);
        let mut bb = [u32::MAX, u32::MAX, 0, 0];
        while let Some(p) = stack.pop() {
            let (u, v) = (p % width, p / width);
            n += 1;
            su += u as u64;
            sv += v as u64;
            bb = [
                bb[0].min(u as u32),
                bb[1].min(v as u32),
                bb[2].max(u as u32),
                bb[3].max(v as u32),
            ];
            let u0 = u.saturating_sub(1);
            let u1 = (u + 1).min(width - 1);
            let v0 = v.saturating_sub(1);
            let v1 = (v + 1).min(height - 1);
            for vv in v0..=v1 {
                for uu in u0..=u1 {
                    let q = uu + width * vv;
                    if image[q] == NONE && labels[q] == lab {
                        image[q] = id;
                        stack.push(q);
                    }
                }
            }
        }
        regions.push(Region {
            label: lab,
            id,
            area: n as u32,
            centroid: [su as f64 / n as f64, sv as f64 / n as f64],
            bbox: bb,
        });
    }
    SliceComponents { image, regions }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn diagonal_pixels_join_and_labels_stay_apart() {
        #[rustfmt::skip]
        let img = [
            1, 0, 0, 2,
            0, 1, 0, 2,
            0, 0, 0, 0,
            3, 3, 0, 1,
        ];
        let c = label_components(&img, 4, 4, |l| l != 0);
        let labs: Vec<(u16, u32)> = c.regions.iter().map(|r| (r.label, r.area)).collect();
        assert_eq!(labs, vec![(1, 2), (2, 2), (3, 2), (1, 1)]);
        assert_eq!(c.regions[0].centroid, [0.5, 0.5]);
        assert_eq!(c.image[2], u32::MAX);
    }
}
