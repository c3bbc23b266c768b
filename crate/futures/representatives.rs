use crate::model::k_means::{as_f64, distance, nearest, KMeans};

/// The indices (increasing) of `k` representatives of `points` (rows of one length): their
/// k-means clusters ([`KMeans`]), each cluster's member nearest its centroid. Where S futures
/// should together cover what may happen, S independent draws clump (two alike, a likely
/// outcome missed); S representatives of N ≥ S draws spread over them as the draws' mass
/// does, each still one of the draws (coherent, performable).
/// Deterministic: the same indices natively and in wasm. All of them when `k` ≥ their number.
pub fn representatives(points: &[Vec<f32>], k: usize) -> Vec<usize> {
    let n = points.len();
    if k >= n {
        return (0..n).collect();
    }
    if k == 0 {
        return Vec::new();
    }
    let KMeans { centres, cluster } = KMeans::fit(points, k);
    // Each cluster's member nearest its centre (an empty cluster keeps its start point).
    let mut chosen: Vec<usize> = (0..k)
        .map(|c| {
            let members = (0..n).filter(|&i| cluster[i] == c);
            members
                .min_by(|&a, &b| {
                    distance(&centres[c], &points[a]).total_cmp(&distance(&centres[c], &points[b]))
                })
                .unwrap_or_else(|| nearest(points, &centres[c]))
        })
        .collect();
    chosen.sort_unstable();
    chosen.dedup();
    // Distinct clusters whose nearest members coincide (possible only for an empty one): fill
    // with the points farthest from those chosen.
    while chosen.len() < k {
        let far = (0..n)
            .filter(|i| !chosen.contains(i))
            .max_by(|&a, &b| {
                let gap = |i: usize| {
                    (chosen.iter())
                        .map(|&c| distance(&as_f64(&points[c]), &points[i]))
                        .fold(f64::INFINITY, f64::min)
                };
                gap(a).total_cmp(&gap(b))
            })
            .unwrap_or(0);
        chosen.push(far);
        chosen.sort_unstable();
    }
    chosen
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn representatives_take_one_from_each_clump() {
        // Three clumps of unequal size on a line, and k = 3: one from each, near its middle.
        let mut points = Vec::new();
        for (centre, count) in [(0.0f32, 20), (10.0, 5), (20.0, 10)] {
            for i in 0..count {
                points.push(vec![centre + (i as f32 - count as f32 / 2.0) * 0.05, 1.0]);
            }
        }
        let chosen = representatives(&points, 3);
        assert_eq!(chosen.len(), 3);
        let mut values: Vec<f32> = chosen.iter().map(|&i| points[i][0]).collect();
        values.sort_by(f32::total_cmp);
        for (v, centre) in values.iter().zip([0.0, 10.0, 20.0]) {
            assert!((v - centre).abs() < 0.3, "{values:?}");
        }
        assert_eq!(representatives(&points, 35), (0..35).collect::<Vec<_>>());
        assert_eq!(representatives(&points, 40).len(), 35);
        assert!(representatives(&points, 0).is_empty());
        // Identical points: still k distinct indices.
        let same = vec![vec![1.0f32, 2.0]; 6];
        let chosen = representatives(&same, 4);
        assert_eq!(chosen.len(), 4);
        assert!(chosen.windows(2).all(|w| w[0] < w[1]));
    }
}
