//! Nearest-camera queries over the unit directions of the cameras: a k-d tree over the unit vectors
//! (O(log n) per query and insensitive to empty regions such as a missing hemisphere). The
//! nearest in chord length is the nearest in great-circle angle; distances come back as
//! great-circle angles, never planar (Δφ, Δθ).

use glam::DVec3;

/// Points per k-d tree leaf.
const LEAF: usize = 8;

/// Great-circle angle (rad) of the chord between two unit vectors, from its squared length.
fn chord2_to_angle(c2: f64) -> f64 {
    2.0 * (c2.max(0.0).sqrt() / 2.0).min(1.0).asin()
}

/// Nearest-camera queries on the unit sphere (a k-d tree over unit vectors; the nearest in chord
/// length is the nearest in great-circle angle).
#[derive(Debug, Clone)]
pub struct CameraIndex {
    /// The points in tree order.
    points: Vec<DVec3>,
    /// Original index of each point.
    ids: Vec<usize>,
    /// Split axis of the node whose median sits at each position.
    axis: Vec<u8>,
}

impl CameraIndex {
    /// An index over `dirs` (unit vectors; query results refer to positions in `dirs`). Non-finite or
    /// zero-length entries are left out.
    pub fn new(dirs: &[DVec3]) -> Self {
        let mut items: Vec<(DVec3, usize)> = dirs
            .iter()
            .enumerate()
            .filter(|(_, d)| d.is_finite() && d.length_squared() > 0.25)
            .map(|(i, d)| (d.normalize(), i))
            .collect();
        let mut axis = vec![0u8; items.len()];
        build(&mut items, 0, &mut axis);
        Self {
            points: items.iter().map(|(p, _)| *p).collect(),
            ids: items.iter().map(|(_, i)| *i).collect(),
            axis,
        }
    }

    /// Number of indexed directions.
    pub fn len(&self) -> usize {
        self.points.len()
    }

    /// Whether no direction is indexed.
    pub fn is_empty(&self) -> bool {
        self.points.is_empty()
    }

    /// The nearest direction to the unit vector `q`: (its index in the input, great-circle angle in
    /// rad); `None` when the index is empty.
    pub fn nearest(&self, q: DVec3) -> Option<(usize, f64)> {
        let mut best = KBest::new(1);
        self.search(0, self.points.len(), q, &mut best);
        best.items.first().map(|&(c2, i)| (self.ids[i], chord2_to_angle(c2)))
    }

    /// The `k` nearest directions to `q`, nearest first, as (index in the input, angle in rad).
    pub fn k_nearest(&self, q: DVec3, k: usize) -> Vec<(usize, f64)> {
        let mut best = KBest::new(k);
        if k > 0 {
            self.search(0, self.points.len(), q, &mut best);
        }
        best.items
            .iter()
            .map(|&(c2, i)| (self.ids[i], chord2_to_angle(c2)))
            .collect()
    }

    fn search(&self, lo: usize, hi: usize, q: DVec3, best: &mut KBest) {
        let n = hi - lo;
        if n <= LEAF {
            for i in lo..hi {
                best.offer((self.points[i] - q).length_squared(), i);
            }
            return;
        }
        let mid = lo + n / 2;
        let a = usize::from(self.axis[mid]);
        let diff = q[a] - self.points[mid][a];
        best.offer((self.points[mid] - q).length_squared(), mid);
        let (near, far) = if diff < 0.0 {
            ((lo, mid), (mid + 1, hi))
        } else {
            ((mid + 1, hi), (lo, mid))
        };
        self.search(near.0, near.1, q, best);
        if diff * diff < best.bound() {
            self.search(far.0, far.1, q, best);
        }
    }
}

/// Builds the implicit k-d tree in place: the median of each range on the axis of largest extent.
fn build(items: &mut [(DVec3, usize)], offset: usize, axis: &mut [u8]) {
    if items.len() <= LEAF {
        return;
    }
    let (mut lo, mut hi) = (DVec3::splat(f64::INFINITY), DVec3::splat(f64::NEG_INFINITY));
    for (p, _) in items.iter() {
        lo = lo.min(*p);
        hi = hi.max(*p);
    }
    let e = hi - lo;
    let a: u8 = if e.x >= e.y && e.x >= e.z {
        0
    } else if e.y >= e.z {
        1
    } else {
        2
    };
    let mid = items.len() / 2;
    let ai = usize::from(a);
    items.select_nth_unstable_by(mid, |x, y| x.0[ai].total_cmp(&y.0[ai]));
    axis[offset + mid] = a;
    let (left, right) = items.split_at_mut(mid);
    build(left, offset, axis);
    build(&mut right[1..], offset + mid + 1, axis);
}

/// The k smallest (squared chord, position) pairs seen, sorted.
struct KBest {
    k: usize,
    items: Vec<(f64, usize)>,
}

impl KBest {
    fn new(k: usize) -> Self {
        Self {
            k,
            items: Vec::with_capacity(k + 1),
        }
    }
    fn bound(&self) -> f64 {
        if self.items.len() < self.k {
            f64::INFINITY
        } else {
            self.items.last().map_or(f64::INFINITY, |x| x.0)
        }
    }
    fn offer(&mut self, d2: f64, i: usize) {
        if d2 >= self.bound() {
            return;
        }
        let at = self.items.partition_point(|x| x.0 <= d2);
        self.items.insert(at, (d2, i));
        self.items.truncate(self.k);
    }
}

#[cfg(test)]
mod tests {
    use super::super::gaps::fibonacci;
    use super::*;

    #[test]
    fn kd_tree_matches_brute_force() {
        let dirs: Vec<DVec3> = (0..2000).map(|i| fibonacci(i * 7 % 2000, 2000)).collect();
        let index = CameraIndex::new(&dirs);
        for j in 0..300 {
            let q = fibonacci(j, 300).normalize();
            let (i, a) = index.nearest(q).unwrap();
            let brute = dirs
                .iter()
                .map(|d| d.dot(q).clamp(-1.0, 1.0).acos())
                .fold(f64::INFINITY, f64::min);
            assert!((a - brute).abs() < 1e-9, "{a} vs {brute}");
            assert!((dirs[i].dot(q).clamp(-1.0, 1.0).acos() - brute).abs() < 1e-9);
            let k = index.k_nearest(q, 5);
            assert_eq!(k.len(), 5);
            assert!(k.windows(2).all(|w| w[0].1 <= w[1].1));
        }
    }
}
