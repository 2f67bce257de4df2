/* hover.c: one period of the landing's flight code, called from a C program.
 *
 * Build against a tree written by `quadland codegen` (see
 * flight_code_for_another_quadrotor.py): the guidance and the landing step with
 * the scenario's values as their defaults. The quadrotor hovers level at the
 * hover point over a deck at rest: the step's collective thrust is then the
 * weight of the quadrotor it was generated for. Prints the four rotor commands
 * (N) and their sum.
 */
#include <stdio.h>
#include <string.h>

#include "quadland_landing.h"

int main(void)
{
    static ql_landing_params params;
    static ql_landing_state state;
    ql_guidance_params guidance;
    ql_guidance_state gs;
    ql_guidance_cues cues = {0, 0, 0};       /* gear above the deck, the marker seen */
    ql_landing_measurement y;
    ql_position_reference ref;
    ql_landing_output out;
    ql_status status;

    ql_landing_params_init(&params);
    ql_guidance_params_init(&guidance);
    memset(&y, 0, sizeof y);
    y.p_e[2] = guidance.hover_height;        /* at the hover point, level, all at rest */
    ql_landing_state_init(&state, &y);
    ql_guidance_state_init(&gs, &guidance);
    status = ql_guidance_step(&y, &cues, &guidance, 0.004, &gs, &ref);
    if (status == QL_OK) {
        status = ql_landing_step(&y, &ref, &params, 0.004, &state, &out);
    }
    if (status != QL_OK) {
        fprintf(stderr, "hover: %s\n", ql_status_string(status));
        return 1;
    }
    printf("%.17g %.17g %.17g %.17g %.17g\n", (double)out.F_cmd[0], (double)out.F_cmd[1],
           (double)out.F_cmd[2], (double)out.F_cmd[3],
           (double)(out.F_cmd[0] + out.F_cmd[1] + out.F_cmd[2] + out.F_cmd[3]));
    return 0;
}
