use std::hint::black_box;
use std::time::Instant;
use twv_generated::Vehicle8;
use twv_model::Model;
fn main() {
    let m = Vehicle8::with_defaults();
    let mut x = [0.3, 0.5, -0.2, 0.7, -0.4, 1.2, 0.1, 0.35];
    let u = [12.0, -1.5];
    let n = 2_000_000;
    // latency: next x depends on f and jac
    let t = Instant::now();
    for _ in 0..n {
        let mut f = [0.0; 8];
        let j = m.kernel_f_jac_x(&x, &u, &mut f);
        x[0] += 1e-12 * (f[4] + j[20]);
    }
    println!(
        "f_jac_x latency {:.1} ns",
        t.elapsed().as_nanos() as f64 / n as f64
    );
    let t = Instant::now();
    for _ in 0..n {
        let mut f = [0.0; 8];
        m.kernel_f(&x, &u, &mut f);
        x[0] += 1e-12 * f[4];
    }
    println!(
        "f latency {:.1} ns",
        t.elapsed().as_nanos() as f64 / n as f64
    );
    let t = Instant::now();
    for _ in 0..n {
        let mut f = [0.0; 8];
        let j = m.kernel_f_jac_x(black_box(&x), &u, &mut f);
        black_box((f, j));
    }
    println!(
        "f_jac_x throughput {:.1} ns",
        t.elapsed().as_nanos() as f64 / n as f64
    );
    let t = Instant::now();
    for _ in 0..n {
        let (s, c) = twv_model::trig::sin_cos(x[0]);
        x[0] += 1e-12 * (s + c);
    }
    println!(
        "sincos latency {:.1} ns",
        t.elapsed().as_nanos() as f64 / n as f64
    );
    black_box(x);
    let (mut f, mut o) = ([0.0; 8], [[0.0; 8]; 8]);
    let w = [[0.1; 8]; 8];
    let t = Instant::now();
    for _ in 0..n {
        jw8(&m, black_box(&x), &u, black_box(&w), &mut f, &mut o);
        black_box((&f, &o));
    }
    println!(
        "f_jw8 throughput {:.1} ns",
        t.elapsed().as_nanos() as f64 / n as f64
    );
    let t = Instant::now();
    for _ in 0..n {
        let mut f = [0.0; 8];
        let mut ju = [[0.0; 2]; 8];
        let j = m.kernel_f_jac_x_jac_u(black_box(&x), &u, &mut f, &mut ju);
        black_box((f, j, ju));
    }
    println!(
        "scalar f_jac_x_jac_u throughput {:.1} ns per point",
        t.elapsed().as_nanos() as f64 / n as f64
    );
}
#[allow(dead_code)]
fn lanes_main() {}
#[inline(never)]
pub fn jw8(
    m: &Vehicle8,
    x: &[f64; 8],
    u: &[f64; 2],
    w: &[[f64; 8]; 8],
    f: &mut [f64; 8],
    out: &mut [[f64; 8]; 8],
) {
    m.f_jw(x, u, w, f, out);
}
