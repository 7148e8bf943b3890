//! Information-theory core: KSG mutual information, entropies, lagged profiles, surrogates,
//! significance and correlation baselines. Pure functions, no I/O, no async.
