/*
 * stdfds.h - fds 0, 1 and 2 opened to /dev/null when a program starts with
 * any of them closed (issue 24): otherwise the first file it opens (a CSV
 * output, a track) becomes fd 2 and every log line lands among its rows.
 */
#ifndef TRAJD_STDFDS_H
#define TRAJD_STDFDS_H

/* Open /dev/null on each of fds 0..2 that is closed.  Returns 0, or -errno
 * if /dev/null cannot be opened (the caller exits: it cannot know where its
 * messages would go). */
int stdfds_open(void);

#endif
