//! Colour maps of the per-element tissue metrics (paper, Figs. 12–13).

/// What the body surface is coloured by.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum ColorMode {
    /// Skin colour only.
    None,
    /// Surface-area change: white none, blue grown, red shrunk (symmetric scale).
    Area,
    /// Deformation degree (Eq. 5): white none to dark orange (sequential scale).
    Degree,
}

impl ColorMode {
    /// Parses `none|area|degree`.
    pub fn parse(s: &str) -> Option<Self> {
        Some(match s {
            "none" => Self::None,
            "area" => Self::Area,
            "degree" => Self::Degree,
            _ => return None,
        })
    }
}

/// Skin colour (linear RGB).
pub const SKIN: [f32; 3] = [0.93, 0.76, 0.64];
/// Bone colour.
pub const BONE: [f32; 3] = [0.93, 0.91, 0.84];
/// Muscle colour.
pub const MUSCLE: [f32; 3] = [0.62, 0.18, 0.14];
/// The muscle under the cursor: the same red, lighter, so it reads as the same tissue.
pub const HOVERED: [f32; 3] = [0.92, 0.42, 0.32];
/// The selected muscle: gold, apart from every tissue colour.
pub const SELECTED: [f32; 3] = [0.98, 0.78, 0.15];

fn lerp3(a: [f32; 3], b: [f32; 3], t: f32) -> [f32; 3] {
    let t = t.clamp(0.0, 1.0);
    [
        a[0] + (b[0] - a[0]) * t,
        a[1] + (b[1] - a[1]) * t,
        a[2] + (b[2] - a[2]) * t,
    ]
}

/// Diverging map of area change `a` (A/A0 − 1): white at no change, blue for growth, red
/// for shrinkage, on a scale symmetric in log2(A/A0) of half-width `range` (1: the full
/// colours are reached at twice and at half the rest area).
pub fn area_color(a: f32, range: f32) -> [f32; 3] {
    let l = (1.0 + a).max(1e-6).log2();
    let t = if range > 0.0 {
        (l / range).clamp(-1.0, 1.0)
    } else {
        0.0
    };
    const WHITE: [f32; 3] = [0.97, 0.97, 0.97];
    const BLUE: [f32; 3] = [0.10, 0.25, 0.85];
    const RED: [f32; 3] = [0.85, 0.10, 0.08];
    if t >= 0.0 {
        lerp3(WHITE, BLUE, t)
    } else {
        lerp3(WHITE, RED, -t)
    }
}

/// Sequential map of deformation degree `d` (m) on `0..max`: white to dark orange.
pub fn degree_color(d: f32, max: f32) -> [f32; 3] {
    let t = if max > 0.0 {
        (d / max).clamp(0.0, 1.0)
    } else {
        0.0
    };
    if t < 0.5 {
        lerp3([0.97, 0.97, 0.97], [0.99, 0.68, 0.25], t * 2.0)
    } else {
        lerp3([0.99, 0.68, 0.25], [0.55, 0.15, 0.02], (t - 0.5) * 2.0)
    }
}

/// The scale to use for a set of values: the 98th percentile of |v|, at least `floor`.
pub fn robust_range(values: &[f32], floor: f32) -> f32 {
    let mut v: Vec<f32> = values
        .iter()
        .map(|x| x.abs())
        .filter(|x| x.is_finite())
        .collect();
    if v.is_empty() {
        return floor;
    }
    v.sort_by(f32::total_cmp);
    v[((v.len() - 1) as f32 * 0.98) as usize].max(floor)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn area_colours_are_white_blue_red() {
        let w = area_color(0.0, 1.0);
        assert!(w.iter().all(|c| *c > 0.9));
        let b = area_color(1.0, 1.0); // doubled
        assert!(b[2] > 0.8 && b[0] < 0.2);
        let r = area_color(-0.5, 1.0); // halved
        assert!(r[0] > 0.8 && r[2] < 0.2);
        assert_eq!(area_color(5.0, 1.0), b, "clamped");
        // Symmetric: doubling and halving are equally strong.
        let (g, s) = (area_color(0.41, 1.0), area_color(-0.29, 1.0));
        assert!((g[2] - s[0]).abs() < 0.05);
    }

    #[test]
    fn degree_colours_darken_with_degree_and_ranges_are_robust() {
        let lo = degree_color(0.0, 0.01);
        let hi = degree_color(0.01, 0.01);
        assert!(lo.iter().sum::<f32>() > hi.iter().sum::<f32>());
        let mut v = vec![0.01f32; 99];
        v.push(100.0);
        assert!((robust_range(&v, 0.001) - 0.01).abs() < 1e-6);
        assert_eq!(robust_range(&[], 0.2), 0.2);
    }
}
