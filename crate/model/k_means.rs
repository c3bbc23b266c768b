/// k-means clusters of points (rows of one length): centres from a farthest-first start (the
/// point nearest the mean first, then each next the point farthest from the centres so far),
/// then Lloyd's iterations until no point changes cluster. Deterministic (f64 sums in a fixed
/// order): the same clusters natively and in wasm. Shared by the futures' representatives and
/// the joint correlation's regions.
#[derive(Debug, Clone, PartialEq)]
pub struct KMeans {
    /// The k centres.
    pub centres: Vec<Vec<f64>>,
    /// Each point's cluster, an index into `centres`.
    pub cluster: Vec<usize>,
}

impl KMeans {
    /// The clusters of `points`, 1 ≤ `k` ≤ their number (fewer distinct points than k: some
    /// clusters stay empty, each keeping its start point as its centre).
    pub fn fit(points: &[Vec<f32>], k: usize) -> KMeans {
        let n = points.len();
        assert!((1..=n).contains(&k), "k-means: k = {k} of {n} points");
        let dim = points[0].len();
        let mean: Vec<f64> = (0..dim)
            .map(|j| points.iter().map(|p| p[j] as f64).sum::<f64>() / n as f64)
            .collect();
        let mut centres = vec![as_f64(&points[nearest(points, &mean)])];
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
        let mut cluster = vec![usize::MAX; n];
        for _ in 0..100 {
            let next: Vec<usize> = (points.iter())
                .map(|p| nearest_centre(centres.iter().map(Vec::as_slice), p))
                .collect();
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
        KMeans { centres, cluster }
    }
}

/// Squared distance between a centre and a point.
pub fn distance(a: &[f64], b: &[f32]) -> f64 {
    a.iter().zip(b).map(|(x, &y)| (x - y as f64).powi(2)).sum()
}

/// The index of the centre nearest `point` (the first of equals; 0 without centres).
pub fn nearest_centre<'a>(centres: impl IntoIterator<Item = &'a [f64]>, point: &[f32]) -> usize {
    (centres.into_iter().enumerate())
        .map(|(i, centre)| (i, distance(centre, point)))
        .min_by(|a, b| a.1.total_cmp(&b.1))
        .map_or(0, |(i, _)| i)
}

/// The index of the point nearest `centre`.
pub fn nearest(points: &[Vec<f32>], centre: &[f64]) -> usize {
    (0..points.len())
        .min_by(|&a, &b| distance(centre, &points[a]).total_cmp(&distance(centre, &points[b])))
        .unwrap_or(0)
}

/// A point in f64.
pub fn as_f64(p: &[f32]) -> Vec<f64> {
    p.iter().map(|&v| v as f64).collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn two_clumps_make_two_clusters() {
        let mut points: Vec<Vec<f32>> = (0..10).map(|i| vec![i as f32 * 0.01, 0.0]).collect();
        points.extend((0..5).map(|i| vec![5.0 + i as f32 * 0.01, 1.0]));
        let k = KMeans::fit(&points, 2);
        assert!(k.cluster[..10].iter().all(|&c| c == k.cluster[0]));
        assert!(k.cluster[10..].iter().all(|&c| c == k.cluster[10]));
        assert_ne!(k.cluster[0], k.cluster[10]);
        let far = &k.centres[k.cluster[10]];
        assert!(
            (far[0] - 5.02).abs() < 1e-6 && (far[1] - 1.0).abs() < 1e-9,
            "{far:?}"
        );
        let centres = k.centres.iter().map(Vec::as_slice);
        assert_eq!(nearest_centre(centres, &[4.0, 1.0]), k.cluster[10]);
        assert_eq!(KMeans::fit(&points, 1).cluster, vec![0; 15]);
    }
}
