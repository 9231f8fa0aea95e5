/* See progress.h. POSIX: sigaction and isatty. */
#include "progress.h"

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

void rt_progress_install_sigint(void)
{
    struct sigaction sa;
    memset(&sa, 0, sizeof sa);
    sa.sa_handler = on_sigint;
    sigemptyset(&sa.sa_mask);
    sigaction(SIGINT, &sa, NULL);
}

int rt_progress_interrupted(void)
{
    return interrupted != 0;
}

void rt_progress_report(FILE *out, unsigned done, unsigned total, double seconds)
{
    double eta = done ? seconds / done * (double)(total - done) : 0.0;
    if (isatty(fileno(out))) {
        enum { WIDTH = 30 };
        unsigned fill = total ? (unsigned)((unsigned long long)WIDTH * done / total) : WIDTH;
        char bar[WIDTH + 1];
        for (unsigned i = 0; i < WIDTH; ++i)
            bar[i] = i < fill ? '#' : '.';
        bar[WIDTH] = '\0';
        fprintf(out, "\r[%s] %u/%u samples  %.1f s  ETA %.1f s ", bar, done, total, seconds, eta);
    } else {
        fprintf(out, "sample %u/%u  %.1f s  ETA %.1f s\n", done, total, seconds, eta);
    }
    fflush(out);
}

void rt_progress_finish(FILE *out)
{
    if (isatty(fileno(out)))
        fputc('\n', out);
}
