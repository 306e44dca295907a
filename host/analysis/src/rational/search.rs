//! The search over counts of terms, shared by the fit and by fit-bench's
//! run of ALTA: galloping (`first`, twice as many, … up to `most`)
//! brackets the fewest count that holds within a factor of two, so that
//! the costliest programme solved has at most twice the answer's terms; a
//! bisection inside the bracket then finds it to one term, as ALTA's own
//! walk (one term at a time from one) does in far more programmes.
//!
//! Sound where holding is monotone in the count: a basis of `n` terms is
//! a prefix of that of `n + 1` (`basis`), so a function of `n` terms is
//! one of `n + 1` with a zero appended. The positivity grid grows with the
//! degree (`qp`), so across a degree's boundary it is not strictly so; the
//! search then answers a count that holds, not always the fewest.

/// The fewest count in `lo..=most` for which `holds` gives `Ok(Ok(_))`,
/// with its value; counts below `lo` are taken not to hold. `Ok(Err(_))`
/// is what `holds` said of `most` when nothing held; an outer `Err` stops
/// the search.
pub fn fewest<T, W, E>(
    mut lo: usize,
    first: usize,
    most: usize,
    mut holds: impl FnMut(usize) -> Result<Result<T, W>, E>,
) -> Result<Result<T, W>, E> {
    let mut n = first.min(most);
    let mut best = loop {
        match holds(n)? {
            Ok(found) => break found,
            Err(why) if n >= most => return Ok(Err(why)),
            Err(_) => {
                lo = n + 1;
                n = (2 * n).min(most);
            }
        }
    };
    let mut hi = n;
    while lo < hi {
        let mid = lo + (hi - lo) / 2;
        match holds(mid)? {
            Ok(found) => {
                best = found;
                hi = mid;
            }
            Err(_) => lo = mid + 1,
        }
    }
    Ok(Ok(best))
}

#[cfg(test)]
mod tests {
    use super::fewest;

    #[test]
    fn finds_the_threshold_in_few_tries_and_says_why_when_none_holds() {
        for threshold in 1..=300 {
            let mut tried = Vec::new();
            let found = fewest::<_, _, ()>(1, 1, 256, |n| {
                tried.push(n);
                Ok(if n >= threshold { Ok(n) } else { Err(n) })
            });
            if threshold <= 256 {
                assert_eq!(found, Ok(Ok(threshold)));
                // Doubling to the bracket, then halving it: 2·log2 + 1.
                assert!(tried.len() <= 17, "{threshold}: {tried:?}");
                assert!(tried.iter().all(|&n| n <= (2 * threshold).min(256)), "{threshold}: {tried:?}");
            } else {
                assert_eq!(found, Ok(Err(256)));
            }
        }
        // A lower bound already known is not tried again.
        let mut tried = Vec::new();
        let found = fewest::<_, (), ()>(9, 16, 16, |n| {
            tried.push(n);
            Ok(Ok(n))
        });
        assert_eq!(found, Ok(Ok(9)));
        assert!(tried.iter().all(|&n| n >= 9));
        assert_eq!(fewest::<usize, (), _>(1, 1, 8, |_| Err("stop")), Err("stop"));
    }
}
