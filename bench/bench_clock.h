/* A monotonic clock for the benchmarks, in ns: clock_gettime on POSIX, QueryPerformanceCounter on
 * Windows (which has no clock_gettime), so that the cross builds compile every benchmark. */
#ifndef DFO_BENCH_CLOCK_H
#define DFO_BENCH_CLOCK_H

#ifdef _WIN32
#include <windows.h>
static double bench_now_ns(void)
{
    LARGE_INTEGER f, c;
    QueryPerformanceFrequency(&f);
    QueryPerformanceCounter(&c);
    return 1e9 * ((double)c.QuadPart / (double)f.QuadPart);
}
#else
#include <time.h>
static double bench_now_ns(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return 1e9 * (double)ts.tv_sec + (double)ts.tv_nsec;
}
#endif

#endif
