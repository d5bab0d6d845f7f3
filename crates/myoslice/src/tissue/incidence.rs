//! Which cells meet at each vertex, in compressed rows.

/// For each of `vertices` vertices, the corners of `cells` at it (cell × `N` + corner),
/// in cell order: the corners at `v` are `corners[start[v]..start[v + 1]]`.
pub(crate) fn vertex_corners<const N: usize>(
    vertices: usize,
    cells: &[[u32; N]],
) -> (Vec<u32>, Vec<u32>) {
    let mut start = vec![0u32; vertices + 1];
    for c in cells {
        for &v in c {
            start[v as usize + 1] += 1;
        }
    }
    for v in 0..vertices {
        start[v + 1] += start[v];
    }
    let mut fill = start.clone();
    let mut corners = vec![0u32; cells.len() * N];
    for (ci, c) in cells.iter().enumerate() {
        for (k, &v) in c.iter().enumerate() {
            corners[fill[v as usize] as usize] = (ci * N + k) as u32;
            fill[v as usize] += 1;
        }
    }
    (start, corners)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn each_vertex_lists_the_corners_at_it_in_cell_order() {
        let (start, corners) = vertex_corners(4, &[[0, 1, 2], [2, 1, 3]]);
        assert_eq!(start, vec![0, 1, 3, 5, 6]);
        assert_eq!(corners, vec![0, 1, 4, 2, 3, 5]);
    }
}
