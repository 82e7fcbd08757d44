//! Many datasets in parallel, optionally each started from its neighbour's fit
//! (`--warm-start`, Python's `warm_start=True`).

use rayon::prelude::*;

/// Chains of warm-started fits per thread: a few per thread keep every thread busy to the
/// end while each chain stays long (its first fit is searched).
pub(crate) const CHAINS_PER_THREAD: usize = 4;

/// `fit` applied to every job on the current rayon pool, results in the jobs' order. With
/// `warm`, the jobs run in `CHAINS_PER_THREAD` contiguous chains per thread, each job
/// after the first of its chain given the result of the job before it (`fit(job,
/// Some(previous))`); without, every job runs on its own (`fit(job, None)`).
pub fn in_chains<J, R, F>(jobs: Vec<J>, warm: bool, fit: F) -> Vec<R>
where
    J: Send,
    R: Send,
    F: Fn(J, Option<&R>) -> R + Sync + Send,
{
    in_chains_kept(jobs, warm, fit, |r| r)
}

/// [`in_chains`], each result handed to `keep` as soon as no later job needs it (at once
/// without `warm`, after the next job of its chain with it), and `keep`'s values returned
/// in the jobs' order: a batch that keeps a little of each result (a summary row) holds
/// one whole result per chain at a time.
pub(crate) fn in_chains_kept<J, R, K, F, G>(jobs: Vec<J>, warm: bool, fit: F, keep: G) -> Vec<K>
where
    J: Send,
    R: Send,
    K: Send,
    F: Fn(J, Option<&R>) -> R + Sync + Send,
    G: Fn(R) -> K + Sync + Send,
{
    if !warm {
        return jobs.into_par_iter().map(|j| keep(fit(j, None))).collect();
    }
    let chains = CHAINS_PER_THREAD * rayon::current_num_threads();
    let len = jobs.len().div_ceil(chains).max(1);
    let mut split: Vec<Vec<J>> = Vec::with_capacity(chains);
    for job in jobs {
        if split.last().is_none_or(|c| c.len() == len) {
            split.push(Vec::with_capacity(len));
        }
        split.last_mut().expect("a chain").push(job);
    }
    split
        .into_par_iter()
        .flat_map_iter(|chain| {
            let mut kept: Vec<K> = Vec::with_capacity(chain.len());
            let mut previous: Option<R> = None;
            for job in chain {
                let r = fit(job, previous.as_ref());
                kept.extend(previous.replace(r).map(&keep));
            }
            kept.extend(previous.map(&keep));
            kept
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn chains_keep_the_jobs_order_and_hand_each_job_its_predecessor() {
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(2)
            .build()
            .unwrap();
        let jobs: Vec<usize> = (0..37).collect();
        let warm = pool.install(|| {
            in_chains(
                jobs.clone(),
                true,
                |j, prev: Option<&(usize, Option<usize>)>| (j, prev.map(|p| p.0)),
            )
        });
        assert_eq!(warm.iter().map(|r| r.0).collect::<Vec<_>>(), jobs);
        // 8 chains of 5 (the last of 2): every job but a chain's first sees the one before.
        let firsts: Vec<usize> = warm.iter().filter(|r| r.1.is_none()).map(|r| r.0).collect();
        assert_eq!(firsts, vec![0, 5, 10, 15, 20, 25, 30, 35]);
        assert!(warm.iter().all(|r| r.1.is_none_or(|p| p + 1 == r.0)));
        let cold = pool.install(|| {
            in_chains(jobs.clone(), false, |j, prev: Option<&(usize, bool)>| {
                (j, prev.is_some())
            })
        });
        assert!(cold.iter().enumerate().all(|(k, r)| r.0 == k && !r.1));
        // Keeping a part of each result: the same values in the same order.
        let kept = pool.install(|| {
            in_chains_kept(
                jobs.clone(),
                true,
                |j, prev: Option<&(usize, Option<usize>)>| (j, prev.map(|p| p.0)),
                |r| r.1,
            )
        });
        assert_eq!(kept, warm.iter().map(|r| r.1).collect::<Vec<_>>());
    }
}
