/*
 * cfg_files.h - the files a configuration reads and writes, compared by
 * identity, not by text (issue 24): `a.csv` and `./a.csv`, a symlink and its
 * target, or a hard link are one file.  Refused at check time (cfg_load,
 * --check-config, a reload): any output that is also an input (csv.truncate
 * would empty the track it replays), and two outputs on one file.  Two inputs
 * may share a file; character devices (/dev/null) are never compared.
 *
 * Each transport names its files through transport_t.files (transport.h):
 * it calls add() once per path it reads (output = 0) or writes (output = 1).
 */
#ifndef TRAJD_CFG_FILES_H
#define TRAJD_CFG_FILES_H

#include "cfg.h"

/* A transport's add(): path (absolute, as cfg_get_path made it; "" and "-"
 * are ignored), output 1 if written, line and what for the message
 * ("[object.boat] csv.path"). */
typedef void (*cfg_file_add_fn)(void *ctx, const char *path, int output, int line,
                                const char *what);

/*
 * Collect every transport's files of c and compare them.  Returns 0, or
 * -CFG_EVALUE (*line: the later of the two, why: both named), or
 * -CFG_ENOMEM.
 */
int cfg_files_check(const cfg_t *c, int *line, char *why, size_t whylen);

/*
 * 1 if paths a and b name one file: the same device and inode when both
 * exist; otherwise the same resolved path (the directory made canonical,
 * then the last name).  0 if not (or either is "" / "-" / a character device).
 */
int cfg_same_file(const char *a, const char *b);

#endif
