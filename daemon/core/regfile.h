/*
 * regfile.h - open a file the configuration names (a replay track, a CAN
 * log_in) for reading, at config-check time, only if it is a regular file
 * of bounded size.  A FIFO would block open() (and the daemon with it, for
 * good: SIGTERM is read by the same loop) or never end; a device may never
 * end or act on being opened; a file beyond the cap would be read whole
 * into memory.  All are refused with the reason, before anything is read.
 */
#ifndef TRAJD_REGFILE_H
#define TRAJD_REGFILE_H

#include <stddef.h>

/*
 * Open path read-only (O_CLOEXEC, blocking reads) if it is a regular file of
 * at most max_bytes bytes.  Returns the fd, or -1 with why set to the reason:
 * strerror of the failure (a directory: strerror(EISDIR)), "not a regular
 * file: a FIFO" (a character device, a block device, a socket), or "larger
 * than N bytes".  It is stat()ed before it is opened (a FIFO's open blocks,
 * a device's may act) and fstat()ed after (it may have been replaced).
 */
int regfile_open(const char *path, long long max_bytes, char *why, size_t wl);

/*
 * Started as root with [daemon] user: the files trajd creates for writing (a
 * CSV output, a CAN log_out) belong to that user, so that after the drop a
 * reload can open them again (as root's, the first reload of an unchanged
 * file was refused and the output closed for good).  regfile_owner sets the
 * owner (main, before anything is opened); regfile_create opens path with
 * flags (O_CREAT among them) and mode, giving a file it created (O_EXCL
 * first) to that owner.  Returns the fd or -1 (errno).  A file that was
 * there is left as it is.
 */
void regfile_owner(unsigned uid, unsigned gid);
int regfile_create(const char *path, int flags, unsigned mode);

#endif
