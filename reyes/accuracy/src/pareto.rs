//! The Pareto front of settings measured by cost and error: the ones no other setting beats on
//! both.

/// For each (cost, error) point, whether it is on the front: no other point has cost and
/// error both at most its own and one of them smaller. Points with a non-finite coordinate
/// are never on it (and beat nothing). Lower is better in both.
pub fn pareto_front(points: &[(f64, f64)]) -> Vec<bool> {
    let ok = |p: &(f64, f64)| p.0.is_finite() && p.1.is_finite();
    points
        .iter()
        .map(|p| {
            ok(p)
                && !points
                    .iter()
                    .any(|q| ok(q) && q.0 <= p.0 && q.1 <= p.1 && (q.0 < p.0 || q.1 < p.1))
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn front_of_a_known_set() {
        let pts = [
            (1.0, 5.0),      // on: cheapest
            (2.0, 3.0),      // on
            (2.5, 3.0),      // off: (2, 3) is cheaper at the same error
            (3.0, 4.0),      // off: beaten by (2, 3)
            (4.0, 1.0),      // on: most accurate
            (4.0, 1.0),      // on: an equal twin does not beat it
            (f64::NAN, 0.1), // off: not measured
            (5.0, f64::INFINITY),
        ];
        assert_eq!(
            pareto_front(&pts),
            [true, true, false, false, true, true, false, false]
        );
        assert!(pareto_front(&[]).is_empty());
    }
}
