//! Tracking regions from slice to slice by overlap: which regions form one tube.

use std::collections::BTreeMap;

use crate::slices::SliceComponents;

/// A chain of regions of one label on consecutive kept slices.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Track {
    /// Label id.
    pub label: u16,
    /// First kept slice.
    pub first_slice: usize,
    /// Component id on each slice from `first_slice` on.
    pub regions: Vec<u32>,
}

/// Links each region to at most one region of the same label on the next slice: the pair
/// must be each other's largest overlap (mutual best). Regions that start, end, split off
/// or merge in begin or end their own tracks (and get caps, never holes).
///
/// `active[s][id]` says whether region `id` of slice `s` takes part (e.g. large enough).
pub fn track_regions(slices: &[&SliceComponents], active: &[Vec<bool>]) -> Vec<Track> {
    let mut tracks: Vec<Track> = Vec::new();
    // Track index of each region on the previous slice.
    let mut prev_track: Vec<Option<usize>> = Vec::new();
    for s in 0..slices.len() {
        let cur = slices[s];
        let mut cur_track: Vec<Option<usize>> = vec![None; cur.regions.len()];
        if s > 0 {
            let prev = slices[s - 1];
            let links = mutual_best(prev, cur, &active[s - 1], &active[s]);
            for (a, b) in links {
                if let Some(t) = prev_track[a as usize] {
                    tracks[t].regions.push(b);
                    cur_track[b as usize] = Some(t);
                }
            }
        }
        for (id, r) in cur.regions.iter().enumerate() {
            if cur_track[id].is_none() && active[s][id] {
                cur_track[id] = Some(tracks.len());
                tracks.push(Track {
                    label: r.label,
                    first_slice: s,
                    regions: vec![id as u32],
                });
            }
        }
        prev_track = cur_track;
    }
    tracks
}

fn mutual_best(
    a: &SliceComponents,
    b: &SliceComponents,
    act_a: &[bool],
    act_b: &[bool],
) -> Vec<(u32, u32)> {
    const NONE: u32 = u32::MAX;
    let mut overlap: BTreeMap<(u32, u32), u32> = BTreeMap::new();
    for (&ia, &ib) in a.image.iter().zip(&b.image) {
        if ia != NONE
            && ib != NONE
            && act_a[ia as usize]
            && act_b[ib as usize]
            && a.regions[ia as usize].label == b.regions[ib as usize].label
        {
            *overlap.entry((ia, ib)).or_insert(0) += 1;
        }
    }
    let mut best_b: Vec<Option<(u32, u32)>> = vec![None; a.regions.len()];
    let mut best_a: Vec<Option<(u32, u32)>> = vec![None; b.regions.len()];
    for (&(ia, ib), &n) in &overlap {
        let ba = &mut best_b[ia as usize];
        if ba.is_none_or(|(m, _)| n > m) {
            *ba = Some((n, ib));
        }
        let bb = &mut best_a[ib as usize];
        if bb.is_none_or(|(m, _)| n > m) {
            *bb = Some((n, ia));
        }
    }
    let mut links = Vec::new();
    for (ia, bb) in best_b.iter().enumerate() {
        if let Some((_, ib)) = bb
            && best_a[*ib as usize].map(|(_, x)| x) == Some(ia as u32)
        {
            links.push((ia as u32, *ib));
        }
    }
    links
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::slices::label_components;

    fn comps(rows: &[&str]) -> SliceComponents {
        let w = rows[0].len();
        let lab: Vec<u16> = rows
            .iter()
            .flat_map(|r| r.bytes().map(|c| if c == b'#' { 1 } else { 0 }))
            .collect();
        label_components(&lab, w, rows.len(), |l| l == 1)
    }

    #[test]
    fn a_split_continues_the_larger_branch_and_starts_a_new_track() {
        let s0 = comps(&["######..", "######..", "........"]);
        let s1 = comps(&["####..##", "####..##", "........"]);
        let s2 = comps(&["####..##", "........", "........"]);
        let slices = [s0, s1, s2];
        let active: Vec<Vec<bool>> = slices.iter().map(|s| vec![true; s.regions.len()]).collect();
        let refs: Vec<&SliceComponents> = slices.iter().collect();
        let t = track_regions(&refs, &active);
        assert_eq!(t.len(), 2);
        assert_eq!(t[0].regions.len(), 3);
        assert_eq!((t[1].first_slice, t[1].regions.len()), (1, 2));
    }
}
