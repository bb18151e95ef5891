//! divan benchmarks (`cargo bench -p kappe-robot`); the table with targets is
//! `examples/bench_table.rs`.

use kappe_robot::collision::{CapsuleSpec, RobotModel};
use kappe_robot::{Joints, UR10E};

fn main() {
    divan::main();
}

const Q: Joints = [0.4, -1.2, 1.1, -1.4, 0.9, 0.7];

#[divan::bench]
fn ik_all_solutions(b: divan::Bencher) {
    let t = UR10E.fk(&Q);
    b.bench(|| UR10E.ik(divan::black_box(&t)).len());
}

#[divan::bench]
fn fk_flange(b: divan::Bencher) {
    b.bench(|| UR10E.fk(divan::black_box(&Q)));
}

#[divan::bench]
fn self_collision(b: divan::Bencher) {
    let model = RobotModel::ur10e_with_tool(&[CapsuleSpec {
        link: 7,
        name: "nozzle".into(),
        a: [0.0, 0.0, 0.02],
        b: [0.0, 0.0, 0.23],
        radius: 0.04,
    }])
    .unwrap();
    b.bench(|| model.self_collides(divan::black_box(&Q), 0.0));
}
