/*
 * Progress of a progressive render: a bar with the ETA on a terminal (one
 * line redrawn in place), plain lines otherwise, and Ctrl-C (SIGINT) turned
 * into a request to stop after the current sample, so that the image so far
 * is written before the program exits.
 */
#ifndef SLUICE_RT_PROGRESS_H
#define SLUICE_RT_PROGRESS_H

#include <stdio.h>

/** Installs the SIGINT handler (the first Ctrl-C asks to stop; a second one
 *  gets the default action and ends the program at once). */
void rt_progress_install_sigint(void);

/** Non-zero once Ctrl-C was pressed. */
int rt_progress_interrupted(void);

/** Reports `done` of `total` samples after `seconds` to `out`: a redrawn bar
 *  when `out` is a terminal, else a plain line. */
void rt_progress_report(FILE *out, unsigned done, unsigned total, double seconds);

/** Ends the bar's line on a terminal. */
void rt_progress_finish(FILE *out);

#endif
