/* The one clock of the renderers: monotonic wall time in seconds, for
 * statistics, progress and time budgets (never for anything a result
 * depends on). */
#ifndef SR_CLOCK_H
#define SR_CLOCK_H

/** Seconds since an arbitrary fixed point (CLOCK_MONOTONIC). */
double sr_clock_seconds(void);

#endif /* SR_CLOCK_H */
