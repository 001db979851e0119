/*
 * A C program of the kind firmware is written in, against include/twv_firmware.h and
 * libtwv_firmware.a: f at a state and the closed loop after a number of RK4 steps, printed as
 * bits in the lines of twv_firmware::case ("f ...", "rk4 ...", "status N") so that
 * .ci/cortex-m-test.sh compares them with the Rust and Cortex-M4 runs of the same case.
 *
 *   check KP KD AMPLITUDE F_MAX H STEPS X0..X7 U0 U1
 */
#include <inttypes.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "twv_firmware.h"

static void line(const char *name, const double *v, int n) {
    printf("%s", name);
    for (int i = 0; i < n; i++) {
        uint64_t bits;
        memcpy(&bits, &v[i], sizeof bits);
        printf(" %016" PRIx64, bits);
    }
    printf("\n");
}

int main(int argc, char **argv) {
    enum { NX = TWV_VEHICLE8_NX, NU = TWV_VEHICLE8_NU };
    if (argc != 7 + NX + NU) {
        fprintf(stderr, "usage: check KP KD AMPLITUDE F_MAX H STEPS X0..X7 U0 U1\n");
        return 2;
    }
    twv_pitch_pd pd = {strtod(argv[1], NULL), strtod(argv[2], NULL), strtod(argv[3], NULL),
                       strtod(argv[4], NULL)};
    double h = strtod(argv[5], NULL);
    uint32_t steps = (uint32_t)strtoul(argv[6], NULL, 10);
    double p[TWV_VEHICLE8_NP], x[NX], u[NU], dx[NX];
    for (int i = 0; i < NX; i++) x[i] = strtod(argv[7 + i], NULL);
    for (int j = 0; j < NU; j++) u[j] = strtod(argv[7 + NX + j], NULL);
    if (twv_vehicle8_defaults(p) != TWV_OK) return 1;
    int f_status = twv_vehicle8_f(p, x, u, dx);
    line("f", dx, NX);
    int status = twv_vehicle8_pd_rk4(p, &pd, x, h, steps);
    line("rk4", x, NX);
    printf("status %d\n", status);
    /* A NULL pointer is refused, not dereferenced. */
    if (twv_vehicle8_f(NULL, x, u, dx) != TWV_NULL_POINTER) return 1;
    return f_status == TWV_OK ? 0 : 1;
}
