//! Debugging aid (ignored).
use mpmwatch::diagnose::candidates::Term;
use mpmwatch::diagnose::select::{fit_term, score};
use mpmwatch::diagnose::{dither_driven, fit_pct, instrument_ctx, output_ctx, select::Split};
use mpmwatch::sim::scenarios::{casebook_specs, run};

#[test]
#[ignore]
fn debug_case() {
    let name = std::env::var("CASE").unwrap_or("c09".into());
    let spec = casebook_specs(3000, 100).into_iter().find(|s| s.name.starts_with(&name)).unwrap();
    let rec = run(&spec).unwrap();
    let (ci, cj) = spec.channel;
    let u: Vec<&[f64]> = rec.u.iter().map(|x| x.as_slice()).collect();
    let n = 3000;
    let n_train = 2100;
    let split =
        Split { features: None, fit: 20..1490, validate: 1490..n_train, train: 20..n_train, folds: vec![] };
    let ctx = output_ctx(&u, &rec.y[cj], &rec.s[cj], &split);
    let d: Vec<&[f64]> = rec.d.iter().map(|x| x.as_slice()).collect();
    let ud: Vec<Vec<f64>> = u.iter().map(|x| dither_driven(x, &d, 20..n_train)).collect();
    let inst = instrument_ctx(&ctx, &ud);
    let r: Vec<f64> = (0..n).map(|t| rec.y[cj][t] - rec.s[cj][t]).collect();
    let uu = &rec.u[ci];
    eprintln!(
        "u range {:?} {:?}, first {:?}",
        uu.iter().cloned().fold(f64::MAX, f64::min),
        uu.iter().cloned().fold(f64::MIN, f64::max),
        &uu[..5]
    );
    eprintln!("u0 {:?} model a {:?} b {:?} fit {}", ctx.u0, ctx.model.a, ctx.model.b, ctx.model.fit_pct);
    let rows: Vec<usize> = (20..1490).collect();

    for t in [
        Term::Gain,
        Term::DeadZone { centre: 0.378, w: 0.55 },
        Term::Cubic,
        Term::Quadratic,
        Term::SaturationIn { lo: -0.9, hi: 0.9 },
        Term::SaturationIn { lo: f64::NEG_INFINITY, hi: 0.9 },
        Term::Backlash(1.5),
    ] {
        let f = fit_term(&ctx, &inst, &r, ci, t.clone(), &rows).unwrap();
        let s_plain = score(&ctx, None, &r, Some(f.clone()), &rows, 1490..n_train, 1.0).unwrap();
        let s_proj = score(&ctx, Some(&inst), &r, Some(f.clone()), &rows, 1490..n_train, 1.0).unwrap();
        let c = mpmwatch::diagnose::simulate::correction(&ctx, &f).unwrap();
        let yhat: Vec<f64> = (1490..n_train).map(|k| rec.s[cj][k] + c[k]).collect();
        let rr: f64 = (20..n).map(|k| (r[k] - c[k]).powi(2)).sum::<f64>() / n as f64;
        let r0: f64 = (20..n).map(|k| r[k].powi(2)).sum::<f64>() / n as f64;
        eprintln!("ms r {r0:.4} r-c {rr:.4}");
        let e: Vec<f64> = (0..n).map(|k| r[k] - c[k]).collect();
        let cc = mpmwatch::info::correlation::ccf(&rec.d[ci][..2100], &e[..2100], 1..=8).unwrap();
        eprintln!("ccf {:?}", cc.iter().map(|v| (v * 100.0).round() / 100.0).collect::<Vec<_>>());
        eprintln!(
            "{:?} coefs {:?} plain {:.1} proj {:.1} fit {:.1}",
            t,
            f.coefs,
            s_plain.score,
            s_proj.score,
            fit_pct(&rec.y[cj][1490..n_train], &yhat)
        );
    }
    let s0p = score(&ctx, None, &r, None, &rows, 1490..n_train, 1.0).unwrap();
    let s0 = score(&ctx, Some(&inst), &r, None, &rows, 1490..n_train, 1.0).unwrap();
    eprintln!("null plain {:.1} proj {:.1}", s0p.score, s0.score);
}
