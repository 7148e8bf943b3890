//! Predictive controllers: constraints hold at every step, set points are reached.

use mpmwatch_core::model::{DiscreteTf, Hammerstein, MimoModel, StaticMap};
use mpmwatch_sim::cases::{continuous2x3, hammerstein3x3};
use mpmwatch_sim::{ClosedLoop, LinearMpc, LoopRecord, MpcConfig, Nmpc};

fn siso(map: StaticMap) -> MimoModel {
    let g = DiscreteTf::new(vec![0.0, 0.5], vec![1.0, -0.8], 0).unwrap();
    MimoModel::new(vec![vec![Some(Hammerstein::new(map, g).unwrap())]]).unwrap()
}

fn quiet_loop(
    model: &MimoModel,
    n: usize,
    r: f64,
    u0: f64,
    ctrl: &mut impl mpmwatch_sim::Controller,
) -> LoopRecord {
    let zeros = vec![vec![0.0; n]];
    ClosedLoop {
        plant: model,
        nominal: model,
        dither: &zeros,
        noise: &zeros,
        setpoint: &[r],
        u_start: &[u0],
        warm_up: 50,
        bound: 1e6,
    }
    .run(ctrl)
    .unwrap()
}

fn assert_feasible(cfg: &MpcConfig, u_init: &[f64], uc: &[Vec<f64>]) -> (usize, usize) {
    let (mut at_bound, mut at_move) = (0, 0);
    for (i, series) in uc.iter().enumerate() {
        let mut prev = u_init[i];
        for (t, &u) in series.iter().enumerate() {
            assert!(
                u >= cfg.u_min[i] && u <= cfg.u_max[i],
                "input {} at t={t}: {u} outside [{}, {}]",
                i + 1,
                cfg.u_min[i],
                cfg.u_max[i]
            );
            assert!(
                (u - prev).abs() <= cfg.du_max[i] + 1e-12,
                "input {} at t={t}: move {} beyond {}",
                i + 1,
                u - prev,
                cfg.du_max[i]
            );
            if (u - cfg.u_min[i]).abs() < 1e-6 || (u - cfg.u_max[i]).abs() < 1e-6 {
                at_bound += 1;
            }
            if ((u - prev).abs() - cfg.du_max[i]).abs() < 1e-6 {
                at_move += 1;
            }
            prev = u;
        }
    }
    (at_bound, at_move)
}

#[test]
fn siso_mpc_limits_moves_and_reaches_the_set_point() {
    let model = siso(StaticMap::Identity);
    let cfg = MpcConfig {
        np: 15,
        nc: 3,
        q: vec![1.0],
        r: vec![0.01],
        u_min: vec![-1.0],
        u_max: vec![0.45],
        du_max: vec![0.1],
    };
    let mut mpc = LinearMpc::new(&model, vec![0.0], vec![0.0], cfg.clone()).unwrap();
    let rec = quiet_loop(&model, 80, 1.0, 0.0, &mut mpc);
    let (_, at_move) = assert_feasible(&cfg, &[0.0], &rec.uc);
    assert!((rec.uc[0][0] - 0.1).abs() < 1e-9, "the first move is limited: {}", rec.uc[0][0]);
    assert!(at_move >= 3, "the move limit was active");
    assert!((rec.y[0][79] - 1.0).abs() < 1e-4, "tracks: y = {}", rec.y[0][79]);
    assert_eq!(mpc.stats().failures, 0);

    // an unreachable set point (needs u = 0.8) pins the input at its bound
    let mut mpc = LinearMpc::new(&model, vec![0.0], vec![0.0], cfg.clone()).unwrap();
    let rec = quiet_loop(&model, 80, 2.0, 0.0, &mut mpc);
    let (at_bound, _) = assert_feasible(&cfg, &[0.0], &rec.uc);
    assert!(at_bound > 50);
    assert!((rec.y[0][79] - 0.45 * 2.5).abs() < 1e-4);
}

#[test]
fn nmpc_drives_a_square_law_plant_to_its_set_point() {
    let model = siso(StaticMap::Square);
    let cfg = MpcConfig {
        np: 10,
        nc: 3,
        q: vec![1.0],
        r: vec![0.01],
        u_min: vec![0.2],
        u_max: vec![3.0],
        du_max: vec![0.2],
    };
    let mut nmpc = Nmpc::new(model.clone(), vec![1.0], cfg.clone(), 2, 0.5).unwrap();
    // steady state at u = 1 is y = 2.5; set point 5.625 needs u = 1.5
    let rec = quiet_loop(&model, 100, 5.625, 1.0, &mut nmpc);
    assert_feasible(&cfg, &[1.0], &rec.uc);
    assert!((rec.y[0][99] - 5.625).abs() < 1e-3, "y = {}", rec.y[0][99]);
    assert!((rec.uc[0][99] - 1.5).abs() < 1e-3, "u = {}", rec.uc[0][99]);
    assert_eq!(nmpc.stats().failures, 0);
}

#[test]
fn continuous2x3_mpc_respects_its_constraints_at_every_step() {
    let n = 1500;
    let plant = continuous2x3::plant(continuous2x3::MISMATCH_A).unwrap();
    let nominal = continuous2x3::plant(continuous2x3::NOMINAL_A).unwrap();
    let cfg = continuous2x3::mpc_config();
    let u_op = continuous2x3::U_OP.to_vec();
    let mut mpc = LinearMpc::new(
        &continuous2x3::linearised(continuous2x3::NOMINAL_A).unwrap(),
        u_op.clone(),
        u_op.clone(),
        cfg.clone(),
    )
    .unwrap();
    let dither: Vec<Vec<f64>> = (0..3)
        .map(|i| (0..n).map(|t| if (t * (i + 3) / 7) % 2 == 0 { 1.0 } else { -1.0 }).collect())
        .collect();
    let noise: Vec<Vec<f64>> =
        (0..2).map(|j| (0..n).map(|t| 2.0 * ((t as f64) * 0.01 * (j + 1) as f64).sin()).collect()).collect();
    let rec = ClosedLoop {
        plant: &plant,
        nominal: &nominal,
        dither: &dither,
        noise: &noise,
        setpoint: &[0.2, 0.4],
        u_start: &u_op,
        warm_up: 100,
        bound: 1e3,
    }
    .run(&mut mpc)
    .unwrap();
    let (at_bound, at_move) = assert_feasible(&cfg, &u_op, &rec.uc);
    assert!(
        at_bound > 0 && at_move > 0,
        "constraints were active ({at_bound} at a bound, {at_move} at the move limit)"
    );
    assert_eq!(mpc.stats().failures, 0);
    assert!(
        mpc.stats().max_raw_violation < 1e-6,
        "solver answers are feasible before projection: {}",
        mpc.stats().max_raw_violation
    );
    for t in 0..n {
        for i in 0..3 {
            assert_eq!(rec.u[i][t], rec.uc[i][t] + rec.ud[i][t]);
        }
    }
}

#[test]
fn hammerstein_nmpc_respects_its_constraints_at_every_step() {
    let n = 600;
    let plant = hammerstein3x3::plant(hammerstein3x3::Mismatch { g21: true, g31: true });
    let nominal = hammerstein3x3::nominal();
    let cfg = hammerstein3x3::nmpc_config();
    let u_op = hammerstein3x3::U_OP.to_vec();
    let mut nmpc = Nmpc::new(nominal.clone(), u_op.clone(), cfg.clone(), 2, 0.5).unwrap();
    let dither: Vec<Vec<f64>> = (0..3)
        .map(|i| (0..n).map(|t| if (t * (i + 2) / 5) % 2 == 0 { 1.0 } else { -1.0 }).collect())
        .collect();
    let noise = vec![vec![0.0; n]; 3];
    let rec = ClosedLoop {
        plant: &plant,
        nominal: &nominal,
        dither: &dither,
        noise: &noise,
        setpoint: &[3.0, 2.0, 3.0],
        u_start: &u_op,
        warm_up: 100,
        bound: 1e3,
    }
    .run(&mut nmpc)
    .unwrap();
    let (at_bound, at_move) = assert_feasible(&cfg, &u_op, &rec.uc);
    assert!(at_bound + at_move > 0, "constraints were active");
    assert_eq!(nmpc.stats().failures, 0);
}

#[test]
fn bad_controller_designs_are_errors() {
    let model = siso(StaticMap::Identity);
    let ok = MpcConfig {
        np: 10,
        nc: 3,
        q: vec![1.0],
        r: vec![0.1],
        u_min: vec![-1.0],
        u_max: vec![1.0],
        du_max: vec![0.1],
    };
    assert!(LinearMpc::new(&model, vec![0.0], vec![0.0], MpcConfig { nc: 11, ..ok.clone() }).is_err());
    assert!(
        LinearMpc::new(&model, vec![0.0], vec![0.0], MpcConfig { q: vec![1.0, 1.0], ..ok.clone() }).is_err()
    );
    assert!(
        LinearMpc::new(&model, vec![0.0], vec![2.0], ok.clone()).is_err(),
        "initial input outside the bounds"
    );
    assert!(
        LinearMpc::new(&siso(StaticMap::Square), vec![0.0], vec![0.0], ok.clone()).is_err(),
        "nonlinear model"
    );
    assert!(Nmpc::new(model.clone(), vec![0.0], ok.clone(), 0, 0.5).is_err());
    assert!(Nmpc::new(model, vec![0.0], ok, 1, -1.0).is_err());
}
