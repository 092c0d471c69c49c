//! Runs one eq. 11 kernel a fixed number of times, for instruction counts under callgrind
//! (docs/PERFORMANCE.md, "Eq. 11 kernels"):
//! `valgrind --tool=callgrind target/release/examples/eq11_count KERNEL OBSTACLES REPS`.
//! The same poses and worlds as the `eq11_kernels` criterion group.

use sixaxis_core::clearance::{Clearance, Eq11Kernel};
use sixaxis_core::kinematics::PAPER_BETA0_DEG;
use sixaxis_core::scenario::{Cell, ClearanceModel, Scenario};

fn main() {
    let args: Vec<String> = std::env::args().collect();
    let [_, kernel, obstacles, reps] = &args[..] else {
        eprintln!(
            "usage: eq11_count KERNEL(avx|sse2|scalar|lanes|lanes-avx|wide) OBSTACLES(19|200) REPS"
        );
        std::process::exit(2);
    };
    let kernel = match kernel.as_str() {
        "avx" => Eq11Kernel::Avx,
        "sse2" => Eq11Kernel::Sse2,
        "scalar" => Eq11Kernel::Scalar,
        "lanes" => Eq11Kernel::Lanes,
        "lanes-avx" => Eq11Kernel::LanesAvx,
        "wide" => Eq11Kernel::Wide,
        other => panic!("kernel: unknown {other:?}"),
    };
    let reps: usize = reps.parse().expect("REPS: a non-negative integer");
    let s = Scenario::builtin("paper_simple").unwrap();
    let arm = s.arm();
    let b0 = PAPER_BETA0_DEG.map(f64::to_radians);
    let poses: Vec<_> = (0..64)
        .map(|k| {
            let mut q = b0;
            for (i, x) in q.iter_mut().enumerate() {
                *x += ((k * 7 + i * 5) % 29) as f64 * 0.2 - 2.8;
            }
            arm.points_mm(&q)
        })
        .collect();
    let mut cells: Vec<Cell> = s.obstacles.clone();
    let n: usize = obstacles.parse().expect("OBSTACLES: 19 or 200");
    let mut k = 0i32;
    while cells.len() < n {
        cells.push([k % 13 - 6, (k / 13) % 13 - 6, (k * 5) % 9 - 1]);
        k += 1;
    }
    let cl = Clearance::new(
        &cells,
        s.cell_mm,
        ClearanceModel::Centres,
        s.arm_safe_distance,
    )
    .with_eq11_kernel(kernel);
    let mut sum = 0.0;
    for _ in 0..reps {
        for p in std::hint::black_box(&poses) {
            sum += cl.clearance_cells(p);
        }
    }
    println!("{sum}");
}
