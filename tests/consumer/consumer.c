/* A program of someone else's, built against an installed dqjulia (find_package or pkg-config):
 * evaluates one point and prints the library's version and the distance estimate. */
#include <dqjulia/dqjulia.h>
#include <stdio.h>

int main(void) {
    dqj_context context = NULL;
    if (dqj_context_create(&context) != DQJ_OK) return 1;
    const double point[8] = {0.1, 0.2, 0.3, 0, 0, 0, 0, 0};
    dqj_sample sample;
    const dqj_status status = dqj_evaluate_points(context, point, 1, &sample);
    dqj_context_destroy(context);
    if (status != DQJ_OK) return 1;
    if (dqj_version_number() != DQJ_VERSION_NUMBER) return 2;
    printf("dqjulia %s n=%d de=%.6f\n", dqj_version_string(), (int)sample.n, sample.de);
    return 0;
}
