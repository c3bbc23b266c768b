/// The indices (increasing) of `k` representatives of `points` (rows of one length): k-means
/// from a farthest-first start (the point nearest the mean first), each cluster's member
/// nearest its centroid. Where S futures should together cover what may happen, S independent
/// draws clump (two alike, a likely outcome missed); S representatives of N ≥ S draws spread
/// over them as the draws' mass does, each still one of the draws (coherent, performable).
/// Deterministic: the same indices natively and in wasm. All of them when `k` ≥ their number.
pub fn representatives(points: &[Vec<f32>], k: usize) -> Vec<usize> {
    let n = points.len();
    if k >= n {
        return (0..n).collect();
    }
    if k == 0 {
        return Vec::new();
    }
    let dim = points[0].len();
    let distance = |a: &[f64], b: &[f32]| -> f64 {
        a.iter().zip(b).map(|(x, &y)| (x - y as f64).powi(2)).sum()
    };
    let as_f64 = |p: &[f32]| p.iter().map(|&v| v as f64).collect::<Vec<_>>();
    let mean: Vec<f64> = (0..dim)
        .map(|j| points.iter().map(|p| p[j] as f64).sum::<f64>() / n as f64)
        .collect();
    let nearest = |centre: &[f64]| {
        (0..n)
            .min_by(|&a, &b| distance(centre, &points[a]).total_cmp(&distance(centre, &points[b])))
            .unwrap_or(0)
    };
    // Farthest-first: each next centre the point farthest from the centres so far.
    let mut centres = vec![as_f64(&points[nearest(&mean)])];
    let mut gap: Vec<f64> = points.iter().map(|p| distance(&centres[0], p)).collect();
    while centres.len() < k {
        let far = (0..n)
            .max_by(|&a, &b| gap[a].total_cmp(&gap[b]))
            .unwrap_or(0);
        centres.push(as_f64(&points[far]));
        for (g, p) in gap.iter_mut().zip(points) {
            *g = g.min(distance(centres.last().unwrap(), p));
        }
    }
    // Lloyd's iterations until no point changes cluster.
    let mut cluster = vec![usize::MAX; n];
    for _ in 0..100 {
        let assign = |p: &[f32]| {
            (0..k)
                .min_by(|&a, &b| distance(&centres[a], p).total_cmp(&distance(&centres[b], p)))
                .unwrap_or(0)
        };
        let next: Vec<usize> = points.iter().map(|p| assign(p)).collect();
        if next == cluster {
            break;
        }
        cluster = next;
        for (c, centre) in centres.iter_mut().enumerate() {
            let members: Vec<&Vec<f32>> = (points.iter().zip(&cluster))
                .filter(|(_, &m)| m == c)
                .map(|(p, _)| p)
                .collect();
            if !members.is_empty() {
                *centre = (0..dim)
                    .map(|j| {
                        members.iter().map(|p| p[j] as f64).sum::<f64>() / members.len() as f64
                    })
                    .collect();
            }
        }
    }
    // Each cluster's member nearest its centre (an empty cluster keeps its start point).
    let mut chosen: Vec<usize> = (0..k)
        .map(|c| {
            let members = (0..n).filter(|&i| cluster[i] == c);
            members
                .min_by(|&a, &b| {
                    distance(&centres[c], &points[a]).total_cmp(&distance(&centres[c], &points[b]))
                })
                .unwrap_or_else(|| nearest(&centres[c]))
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
