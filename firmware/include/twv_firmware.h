/*
 * twv's kernels for firmware written in C: the study's two-wheeled vehicle (vehicle8), its pitch
 * PD law and fixed-step RK4 of the closed loop. The functions are in the static library
 * libtwv_firmware.a (crate twv-firmware: `cargo build --release -p twv-firmware` for the host,
 * .ci/cortex-m-test.sh for thumbv7em-none-eabihf). No function allocates, blocks or keeps state;
 * all arithmetic is IEEE double precision (software floating point on a Cortex-M4F), so results
 * have the bits of twv's own runs on a PC.
 *
 * States x (SI units): phi [rad], x [m], y [m], theta [rad], w_y [rad/s], v_x [m/s], v_y [m/s],
 * w_z [rad/s]. Inputs u: F1 [N] (pitch force on the pendulum bar), T2 [N m] (yaw torque).
 * Parameters p, in this order: m1, m2, g, a, b, c, I1_xx, I1_yy, I1_zz, I2_xx, I2_yy, I2_zz,
 * R, m_w, J_a, J_d (twv's vehicles/paper.toml; twv_vehicle8_defaults writes the study's).
 */
#ifndef TWV_FIRMWARE_H
#define TWV_FIRMWARE_H

#include <stdint.h>

#ifdef __cplusplus
extern "C" {
#endif

#define TWV_VEHICLE8_NX 8  /* states */
#define TWV_VEHICLE8_NU 2  /* inputs */
#define TWV_VEHICLE8_NP 16 /* parameters */

/* Return values. */
#define TWV_OK 0            /* every result is finite */
#define TWV_NOT_FINITE 1    /* a result is NaN or infinite (the state blew up) */
#define TWV_NULL_POINTER -1 /* a pointer argument was NULL; nothing was written */
#define TWV_BAD_STEP -2     /* the step size is not finite and > 0; nothing was written */
#define TWV_NOT_WIRED -3    /* the model lacks the law's states or input */

/* The pitch law F1 = sat(kp (phi - setpoint_amplitude sin phi) + kd w_y), |F1| <= f_max;
 * T2 = 0. setpoint_amplitude = 0.03 is the study's setpoint; f_max = INFINITY: no limit. */
typedef struct twv_pitch_pd {
    double kp;                 /* [N/rad] */
    double kd;                 /* [N s/rad] */
    double setpoint_amplitude; /* [rad] */
    double f_max;              /* [N] */
} twv_pitch_pd;

/* p[NP] = the study's parameter values. */
int twv_vehicle8_defaults(double *p);

/* dx[NX] = f(x, u; p). */
int twv_vehicle8_f(const double *p, const double *x, const double *u, double *dx);

/* jac[NX * NX] = df/dx, row-major: jac[i * NX + j] = d f_i / d x_j. */
int twv_vehicle8_jac_x(const double *p, const double *x, const double *u, double *jac);

/* jac[NX * NU] = df/du, row-major: jac[i * NU + j] = d f_i / d u_j. */
int twv_vehicle8_jac_u(const double *p, const double *x, const double *u, double *jac);

/* The force the law applies at state x[NX] [N]; NaN for a NULL pointer. */
double twv_pitch_pd_force(const twv_pitch_pd *pd, const double *x);

/* `steps` RK4 steps of size h [s] of the closed loop from x[NX], written back into x. Stops at
 * the first non-finite state (TWV_NOT_FINITE, x holds it). */
int twv_vehicle8_pd_rk4(const double *p, const twv_pitch_pd *pd, double *x, double h,
                        uint32_t steps);

#ifdef __cplusplus
}
#endif

#endif /* TWV_FIRMWARE_H */
