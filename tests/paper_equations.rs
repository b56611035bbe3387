//! The assembled right-hand side equals the paper's hand-written equations:
//! Eq. 2 (stage with friction isolator) and Eq. 3 (without), with the link-force
//! sign of DESIGN.md, at many random states, with and without integral action
//! and a moving reference. Both evaluation paths are checked: the constant-Jacobian
//! path that translational models take, and the general recursive dynamics.

use fistage_model::{Inputs, LugreParams, ReferenceSample};
use fistage_tests::{SplitMix, load};

const M_T: f64 = 1.0;
const M_B: f64 = 0.5;
const K_J: f64 = 40_000.0;
const C_J: f64 = 2.0;

/// Servo force of Eq. 28 with integral action: -k (x - x_r) - c (x' - x_r') - k_i I.
fn servo(k: f64, c: f64, k_i: f64, x: f64, v: f64, integral: f64, r: &ReferenceSample) -> f64 {
    -k * (x - r.position) - c * (v - r.velocity) - k_i * integral
}

fn close(a: f64, b: f64) -> bool {
    (a - b).abs() <= 1e-9 * a.abs().max(b.abs()).max(1e-9)
}

#[test]
fn fi_stage_matches_paper_eq2() {
    for file in [
        "scenarios/paper/fig05b_fi.toml",
        "scenarios/paper/fig12_ki1e6.toml",
    ] {
        let loaded = load(file);
        let model = &loaded.model;
        let controller = model.controller().expect("controller");
        let lugre = LugreParams::paper_table1();
        let names = &model.layout().names;
        let index = |n: &str| {
            names
                .iter()
                .position(|s| s == n)
                .unwrap_or_else(|| panic!("{n}"))
        };
        let (ix, ixb, iv, ivb, iz) = (
            index("table_x.q"),
            index("bearing_x.q"),
            index("table_x.v"),
            index("bearing_x.v"),
            index("bearing_friction.z"),
        );
        let mut ws = model.workspace();
        let mut rng = SplitMix(7);
        let mut dx = vec![0.0; model.n_states()];
        for _ in 0..500 {
            let mut x = model.zero_state();
            x[ix] = rng.range(-1e-3, 1e-3);
            x[ixb] = rng.range(-1e-3, 1e-3);
            x[iv] = rng.range(-0.05, 0.05);
            x[ivb] = rng.range(-0.05, 0.05);
            x[iz] = rng.range(-4e-6, 4e-6);
            if let Some(i) = controller.integral_index {
                x[i] = rng.range(-1e-4, 1e-4);
            }
            let inputs = Inputs {
                reference: ReferenceSample {
                    position: rng.range(-1e-3, 1e-3),
                    velocity: rng.range(-1e-2, 1e-2),
                },
                servo_force: rng.range(-2.0, 2.0),
                platform_velocity: rng.range(-0.03, 0.03),
            };
            model.rhs(&x, &inputs, &mut dx, &mut ws);
            let mut general = vec![0.0; model.n_states()];
            model.rhs_general(&x, &inputs.values(), &mut general, &mut ws);
            for (a, b) in dx.iter().zip(&general) {
                assert!(close(*a, *b), "fast path {a} vs general {b}");
            }

            // Paper Eq. 2 with the DESIGN.md link force f_l = c_j (x' - x_b') + k_j (x - x_b).
            let (xt, xb, vt, vb, z) = (x[ix], x[ixb], x[iv], x[ivb], x[iz]);
            let integral = controller.integral_index.map_or(0.0, |i| x[i]);
            let slip = vb - inputs.platform_velocity;
            let z_rate = slip - slip.abs() / lugre.g(slip) * z;
            let f_f = lugre.sigma0 * z + lugre.sigma1 * z_rate + lugre.sigma2 * slip;
            let f_l = C_J * (vt - vb) + K_J * (xt - xb);
            let f_servo = servo(
                controller.k,
                controller.c,
                controller.k_i,
                xt,
                vt,
                integral,
                &inputs.reference,
            ) + inputs.servo_force;
            let table_accel = (f_servo - f_l) / M_T;
            let bearing_accel = (f_l - f_f) / M_B;

            assert!(close(dx[ix], vt) && close(dx[ixb], vb));
            assert!(
                close(dx[iv], table_accel),
                "{file}: {} vs {table_accel}",
                dx[iv]
            );
            assert!(
                close(dx[ivb], bearing_accel),
                "{file}: {} vs {bearing_accel}",
                dx[ivb]
            );
            assert!(close(dx[iz], z_rate));
            if let Some(i) = controller.integral_index {
                assert!(close(dx[i], xt - inputs.reference.position));
            }
        }
    }
}

#[test]
fn rigid_stage_matches_paper_eq3() {
    let loaded = load("scenarios/paper/fig05b_rigid.toml");
    let model = &loaded.model;
    assert_eq!(
        model.bodies().len(),
        1,
        "bearing must be merged into the table"
    );
    assert!((model.bodies()[0].mass - (M_T + M_B)).abs() < 1e-12);
    let controller = model.controller().expect("controller");
    let lugre = LugreParams::paper_table1();
    let mut ws = model.workspace();
    let mut rng = SplitMix(11);
    let mut dx = vec![0.0; model.n_states()];
    for _ in 0..500 {
        let x = vec![
            rng.range(-1e-3, 1e-3),
            rng.range(-0.05, 0.05),
            rng.range(-4e-6, 4e-6),
        ];
        let inputs = Inputs {
            reference: ReferenceSample::default(),
            servo_force: 0.0,
            platform_velocity: rng.range(-0.03, 0.03),
        };
        model.rhs(&x, &inputs, &mut dx, &mut ws);
        let mut general = vec![0.0; model.n_states()];
        model.rhs_general(&x, &inputs.values(), &mut general, &mut ws);
        for (a, b) in dx.iter().zip(&general) {
            assert!(close(*a, *b), "fast path {a} vs general {b}");
        }
        let slip = x[1] - inputs.platform_velocity;
        let z_rate = slip - slip.abs() / lugre.g(slip) * x[2];
        let f_f = lugre.sigma0 * x[2] + lugre.sigma1 * z_rate + lugre.sigma2 * slip;
        // (m_t + m_b) x'' + f_f + c x' + k x = 0
        let accel = -(f_f + controller.c * x[1] + controller.k * x[0]) / (M_T + M_B);
        assert!(close(dx[0], x[1]));
        assert!(close(dx[1], accel), "{} vs {accel}", dx[1]);
        assert!(close(dx[2], z_rate));
    }
}
