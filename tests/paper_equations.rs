//! The assembled right-hand side equals the paper's hand-written equations:
//! Eq. 2 (stage with friction isolator) and Eq. 3 (without), with the link-force
//! sign of DESIGN.md, at many random states, with and without integral action
//! and a moving reference. Both evaluation paths are checked: the constant-Jacobian
//! path that translational models take, and the general recursive dynamics;
//! and Eq. 2 per bearing for a table on four and on ten bearings along one axis.

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

/// Paper Eq. 2 written for a table on `n` bearings along one axis, each
/// with its own isolator and LuGre friction, as robot XML: bearing `i` has
/// mass, isolator and friction parameters spread by `i`.
fn one_axis_stage(n: usize) -> (String, Vec<(f64, f64, f64, LugreParams)>) {
    let base = LugreParams::paper_table1();
    let mut xml = String::from(
        r#"<robot name="axis" xmlns:fistage="urn:fistage:urdf:1"><link name="world"/>
  <link name="table"><inertial><mass value="1.0"/><inertia ixx="1e-3" ixy="0" ixz="0" iyy="1e-3" iyz="0" izz="1e-3"/></inertial></link>
  <joint name="table_x" type="prismatic"><parent link="world"/><child link="table"/><axis xyz="1 0 0"/><limit lower="-1" upper="1" effort="1" velocity="1"/></joint>
  <fistage:actuator name="drive" link="table"><origin xyz="0 0 0"/><axis xyz="1 0 0"/></fistage:actuator>
  <fistage:sensor name="encoder" link="table"><origin xyz="0 0 0"/><axis xyz="1 0 0"/></fistage:sensor>
"#,
    );
    let mut bearings = Vec::new();
    for i in 0..n {
        let spread = 1.0 + 0.03 * i as f64;
        let (mass, k, c) = (
            0.5 / n as f64 * spread,
            4e4 / n as f64 / spread,
            2.0 * spread,
        );
        let lugre = LugreParams {
            sigma0: base.sigma0 / n as f64 * spread,
            f_c: base.f_c / n as f64 / spread,
            f_s: base.f_s / n as f64,
            ..base
        };
        xml += &format!(
            r#"  <link name="b{i}"><inertial><mass value="{mass:e}"/><inertia ixx="1e-4" ixy="0" ixz="0" iyy="1e-4" iyz="0" izz="1e-4"/></inertial></link>
  <joint name="b{i}_x" type="prismatic"><parent link="world"/><child link="b{i}"/><axis xyz="1 0 0"/><limit lower="-1" upper="1" effort="1" velocity="1"/></joint>
  <fistage:isolator name="iso{i}" parent="table" child="b{i}"><origin xyz="0 0 0" rpy="0 0 0"/><stiffness xyz="{k:e} 0 0" rpy="0 0 0"/><damping xyz="{c:e} 0 0" rpy="0 0 0"/></fistage:isolator>
  <fistage:friction name="f{i}" link="b{i}"><origin xyz="0 0 0"/><axis xyz="1 0 0"/><lugre sigma0="{:e}" sigma1="{:e}" sigma2="{:e}" f_c="{:e}" f_s="{:e}" v_s="{:e}"/></fistage:friction>
"#,
            lugre.sigma0, lugre.sigma1, lugre.sigma2, lugre.f_c, lugre.f_s, lugre.v_s
        );
        bearings.push((mass, k, c, lugre));
    }
    xml += "</robot>";
    (xml, bearings)
}

/// A table on four bearings (5 degrees of freedom, dense rows of fixed
/// length) and on ten (11, sparse rows) along one axis: the fast path and
/// the general dynamics both equal Eq. 2 written out bearing by bearing.
#[test]
fn one_axis_stages_on_many_bearings_match_eq2_per_bearing() {
    const SCENARIO: &str = "robot = \"x\"\nduration = 1.0\n[platform]\nvelocity = 0.02\n[controller]\nsensor = \"encoder\"\nactuator = \"drive\"\nk = 6e4\nc = 100.0\n";
    for n in [4, 10] {
        let (xml, bearings) = one_axis_stage(n);
        let model = fistage_tests::model_from(&xml, SCENARIO);
        let controller = model.controller().expect("controller");
        let names = &model.layout().names;
        let index = |name: String| {
            names
                .iter()
                .position(|s| *s == name)
                .unwrap_or_else(|| panic!("{name}"))
        };
        let (it, ivt) = (index("table_x.q".into()), index("table_x.v".into()));
        let mut ws = model.workspace();
        let mut rng = SplitMix(13 + n as u64);
        let mut dx = vec![0.0; model.n_states()];
        let mut general = vec![0.0; model.n_states()];
        for _ in 0..200 {
            let x: Vec<f64> = names
                .iter()
                .map(|name| match name.rsplit('.').next() {
                    Some("q") => rng.range(-1e-3, 1e-3),
                    Some("v") => rng.range(-0.05, 0.05),
                    _ => rng.range(-2e-6, 2e-6),
                })
                .collect();
            let inputs = Inputs {
                reference: ReferenceSample::default(),
                servo_force: rng.range(-2.0, 2.0),
                platform_velocity: rng.range(-0.03, 0.03),
            };
            model.rhs(&x, &inputs, &mut dx, &mut ws);
            model.rhs_general(&x, &inputs.values(), &mut general, &mut ws);
            let mut table_force = servo(
                controller.k,
                controller.c,
                controller.k_i,
                x[it],
                x[ivt],
                0.0,
                &inputs.reference,
            ) + inputs.servo_force;
            for (i, (mass, k, c, lugre)) in bearings.iter().enumerate() {
                let (ib, ivb, iz) = (
                    index(format!("b{i}_x.q")),
                    index(format!("b{i}_x.v")),
                    index(format!("f{i}.z")),
                );
                let slip = x[ivb] - inputs.platform_velocity;
                let z_rate = slip - slip.abs() / lugre.g(slip) * x[iz];
                let f_f = lugre.sigma0 * x[iz] + lugre.sigma1 * z_rate + lugre.sigma2 * slip;
                let f_l = c * (x[ivt] - x[ivb]) + k * (x[it] - x[ib]);
                table_force -= f_l;
                for rates in [&dx, &general] {
                    assert!(close(rates[ib], x[ivb]));
                    assert!(
                        close(rates[ivb], (f_l - f_f) / mass),
                        "{n} bearings, bearing {i}: {} vs {}",
                        rates[ivb],
                        (f_l - f_f) / mass
                    );
                    assert!(close(rates[iz], z_rate));
                }
            }
            for rates in [&dx, &general] {
                assert!(close(rates[ivt], table_force / M_T), "{n} bearings: table");
            }
        }
    }
}
