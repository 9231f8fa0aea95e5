/* See progressive.h. POSIX: sigaction and isatty. */
#include "progressive.h"
#include "clock.h"

#include <signal.h>
#include <string.h>
#include <unistd.h>

static volatile sig_atomic_t interrupted;

static void on_sigint(int sig)
{
    (void)sig;
    interrupted = 1;
    /* a second Ctrl-C is not caught: the user insists */
    signal(SIGINT, SIG_DFL);
}

void sr_progress_install_sigint(void)
{
    struct sigaction sa;
    memset(&sa, 0, sizeof sa);
    sa.sa_handler = on_sigint;
    sigemptyset(&sa.sa_mask);
    sigaction(SIGINT, &sa, NULL);
}

int sr_progress_interrupted(void)
{
    return interrupted != 0;
}

void sr_progress_report(FILE *out, const char *unit, unsigned done, unsigned total, double seconds,
                        double time_limit)
{
    double frac = total ? (double)done / total : 1.0;
    if (time_limit > 0 && seconds / time_limit > frac)
        frac = seconds / time_limit;
    if (frac > 1.0)
        frac = 1.0;
    double eta = frac > 0 ? seconds / frac - seconds : 0.0;
    if (isatty(fileno(out))) {
        enum { WIDTH = 30 };
        unsigned fill = (unsigned)(WIDTH * frac);
        char bar[WIDTH + 1];
        for (unsigned i = 0; i < WIDTH; ++i)
            bar[i] = i < fill ? '#' : '.';
        bar[WIDTH] = '\0';
        fprintf(out, "\r[%s] %u/%u %s  %.1f s  ETA %.1f s ", bar, done, total, unit, seconds, eta);
    } else {
        fprintf(out, "%u/%u %s  %.1f s  ETA %.1f s\n", done, total, unit, seconds, eta);
    }
    fflush(out);
}

void sr_progress_finish(FILE *out)
{
    if (isatty(fileno(out)))
        fputc('\n', out);
}

sluice_status sr_progressive_run(const sr_progressive *p, sr_step_fn step,
                                 sr_checkpoint_fn checkpoint, void *user,
                                 sr_progressive_result *res)
{
    memset(res, 0, sizeof *res);
    res->error = -1.0;
    if (!p || !step || p->total == 0 || !(p->time_limit >= 0) || !(p->target_error >= 0) ||
        (p->target_error > 0 && !p->estimate))
        return SLUICE_ERROR_INVALID_ARGUMENT;
    FILE *out = p->out ? p->out : stderr;
    const char *unit = p->unit ? p->unit : "steps";
    sr_progress_install_sigint();
    double t0 = sr_clock_seconds();
    sluice_status st = SLUICE_OK;
    while (res->done < p->total) {
        st = step(user);
        if (st != SLUICE_OK)
            break;
        res->done++;
        res->seconds = sr_clock_seconds() - t0;
        if (p->progress)
            sr_progress_report(out, unit, res->done, p->total, res->seconds, p->time_limit);
        if (p->time_limit > 0 && res->seconds >= p->time_limit && res->done < p->total) {
            res->out_of_time = 1;
            break;
        }
        if (sr_progress_interrupted()) {
            res->interrupted = 1;
            break;
        }
        if (p->target_error > 0 && p->estimate(user, &res->error)) {
            res->converged = 1;
            break;
        }
        if (checkpoint && p->checkpoint && res->done % p->checkpoint == 0 && res->done < p->total &&
            (st = checkpoint(user)) != SLUICE_OK)
            break;
    }
    res->seconds = sr_clock_seconds() - t0;
    if (p->progress)
        sr_progress_finish(out);
    return st;
}

void sr_progressive_report_target(const char *prog, const sr_progressive *p,
                                  const sr_progressive_result *res, FILE *out)
{
    if (!(p->target_error > 0))
        return;
    if (res->error < 0)
        fprintf(out, "%s: target relMSE %g: no estimate (too few %s)\n", prog, p->target_error,
                p->unit ? p->unit : "steps");
    else
        fprintf(out, "%s: estimated relMSE %.3g after %u %s: target %g %s\n", prog, res->error,
                res->done, p->unit ? p->unit : "steps", p->target_error,
                res->converged ? "reached" : "not reached");
}
