#include "lcp.h"
#include <stdio.h>
int main(void) {
    const double M[4] = {10, -10, -10, 10}, q[2] = {0.4 - 1.0, 0.4 + 1.0};
    double z[2], w[2]; int zb[2];
    lcp_status s = lcp_lemke(2, M, q, 16, z, w, zb, NULL);
    printf("%d %g %g %g %g\n", s, z[0], z[1], w[0], w[1]);
    return s != LCP_OK;
}
