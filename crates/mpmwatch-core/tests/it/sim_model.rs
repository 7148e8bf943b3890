//! Model simulation against hand-computed responses and closed forms.

use mpmwatch_core::model::{
    Arx, ContinuousTf, DiscreteTf, Hammerstein, Mat, MimoModel, StateSpace, StaticMap,
};

#[test]
fn second_order_step_response_by_hand() {
    // y(t) = 1.2 y(t−1) − 0.35 y(t−2) + 0.3 u(t−1) + 0.2 u(t−2)
    let g = DiscreteTf::new(vec![0.0, 0.3, 0.2], vec![1.0, -1.2, 0.35], 0).unwrap();
    let s = g.step_response(200);
    let hand = [0.0, 0.3, 0.86, 1.427];
    for (k, h) in hand.iter().enumerate() {
        assert!((s[k] - h).abs() < 1e-12, "k={k}: {} vs {h}", s[k]);
    }
    assert!((s[199] - 0.5 / 0.15).abs() < 1e-9, "settles at B(1)/A(1)");
    assert!((g.dc_gain().unwrap() - 0.5 / 0.15).abs() < 1e-12);
}

#[test]
fn zoh_of_first_order_lag_is_exp_minus_t() {
    for t in [0.05, 0.3, 1.0, 3.0] {
        let g = ContinuousTf::new(vec![1.0], vec![1.0, 1.0], 0.0).unwrap().discretise(t).unwrap();
        let pole = -g.denominator()[1];
        assert!((pole - (-t).exp()).abs() < 1e-13, "T={t}: pole {pole}");
        let s = g.step_response(30);
        for (k, v) in s.iter().enumerate() {
            let exact = 1.0 - (-(k as f64) * t).exp();
            assert!((v - exact).abs() < 1e-12, "T={t}, k={k}");
        }
    }
}

#[test]
fn zoh_of_underdamped_second_order_with_dead_time() {
    // 1/(s²+s+1) delayed 2 s, T = 0.5: step response 1 − e^(−t/2)(cos(wt) + sin(wt)/(2w·... )),
    // w = √3/2: y(t) = 1 − e^(−t/2)(cos wt + (1/√3) sin wt)
    let t = 0.5;
    let g = ContinuousTf::new(vec![1.0], vec![1.0, 1.0, 1.0], 2.0).unwrap().discretise(t).unwrap();
    assert_eq!(g.delay(), 4);
    let s = g.step_response(60);
    let w = 3f64.sqrt() / 2.0;
    for (k, v) in s.iter().enumerate() {
        let tau = k as f64 * t - 2.0;
        let exact = if tau <= 0.0 {
            0.0
        } else {
            1.0 - (-tau / 2.0).exp() * ((w * tau).cos() + (w * tau).sin() / 3f64.sqrt())
        };
        assert!((v - exact).abs() < 1e-10, "k={k}: {v} vs {exact}");
    }
}

#[test]
fn state_space_and_transfer_function_agree() {
    let c = ContinuousTf::new(vec![1.0, 2.0], vec![1.0, 2.0, 3.0], 0.0).unwrap();
    let (a, b, cm, d) = c.realisation();
    let ss = StateSpace::zoh(&a, &b, &cm, &d, 0.7).unwrap();
    let tf = c.discretise(0.7).unwrap();
    let u: Vec<f64> = (0..50).map(|k| ((k * 7 % 11) as f64 - 5.0) / 3.0).collect();
    let y_tf = tf.simulate(&u);
    let y_ss = ss.simulate(&u.iter().map(|v| vec![*v]).collect::<Vec<_>>()).unwrap();
    for k in 0..u.len() {
        assert!((y_tf[k] - y_ss[k][0]).abs() < 1e-10, "k={k}");
    }
    assert!((Mat::identity(2, 2).exp()[(0, 0)] - std::f64::consts::E).abs() < 1e-14);
}

#[test]
fn step_api_and_whole_record_agree_for_mimo_hammerstein() {
    let g = |b: Vec<f64>, a: Vec<f64>| DiscreteTf::new(b, a, 0).unwrap();
    let m = MimoModel::new(vec![
        vec![
            Some(Hammerstein::linear(g(vec![0.0, 0.1, 0.2], vec![1.0, -0.8]))),
            Some(Hammerstein::new(StaticMap::Square, g(vec![0.0, 0.3], vec![1.0, -0.5])).unwrap()),
        ],
        vec![None, Some(Hammerstein::new(StaticMap::Sine, g(vec![0.0, 1.0], vec![1.0, 0.4])).unwrap())],
    ])
    .unwrap();
    let u1: Vec<f64> = (0..40).map(|k| (k as f64 * 0.37).sin()).collect();
    let u2: Vec<f64> = (0..40).map(|k| (k as f64 * 0.11).cos()).collect();
    let whole = m.simulate(&[u1.clone(), u2.clone()]).unwrap();
    let mut s = m.state();
    for k in 0..40 {
        let peek = s.peek();
        let y = s.step(&[u1[k], u2[k]]).unwrap();
        assert_eq!(peek, y, "strictly proper: the output is known before the input");
        assert_eq!(y, vec![whole[0][k], whole[1][k]]);
    }
    // by hand: y2(1) = sin(u2(0)) since y2(t) = −0.4 y2(t−1) + sin(u2(t−1))
    assert!((whole[1][1] - u2[0].sin()).abs() < 1e-15);
    assert!((whole[1][2] - (-0.4 * u2[0].sin() + u2[1].sin())).abs() < 1e-15);
}

#[test]
fn arx_channel_matches_its_transfer_function() {
    let arx = Arx::new(vec![1.0, -1.05, 0.136], vec![vec![-0.11, -0.058], vec![0.5]], vec![1, 3]).unwrap();
    let u1: Vec<f64> = (0..30).map(|k| if k % 4 < 2 { 1.0 } else { -1.0 }).collect();
    let u2: Vec<f64> = (0..30).map(|k| k as f64 / 30.0).collect();
    let y = arx.simulate(&[u1.clone(), u2.clone()]).unwrap();
    let g1 = arx.channel(0).unwrap().simulate(&u1);
    let g2 = arx.channel(1).unwrap().simulate(&u2);
    for k in 0..30 {
        assert!((y[k] - g1[k] - g2[k]).abs() < 1e-12);
    }
    // prediction on the simulated output equals the simulation (no noise)
    let p = arx.predict(&[u1, u2], &y).unwrap();
    for k in 0..30 {
        assert!((p[k] - y[k]).abs() < 1e-12);
    }
}
