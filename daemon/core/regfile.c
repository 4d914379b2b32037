/* regfile.c - open a configured input file only if it is regular and bounded (see regfile.h). */
#include "regfile.h"

#include <errno.h>
#include <fcntl.h>
#include <stdio.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

/* 0 if sb is a regular file of at most max_bytes, else -1 with why. */
static int judge(const struct stat *sb, long long max_bytes, char *why, size_t wl)
{
    const char *kind = S_ISFIFO(sb->st_mode)   ? "a FIFO"
                       : S_ISCHR(sb->st_mode)  ? "a character device"
                       : S_ISBLK(sb->st_mode)  ? "a block device"
                       : S_ISSOCK(sb->st_mode) ? "a socket"
                                               : "not a regular file";
    if (S_ISDIR(sb->st_mode)) {
        snprintf(why, wl, "%s", strerror(EISDIR));
        return -1;
    }
    if (!S_ISREG(sb->st_mode)) {
        snprintf(why, wl, "not a regular file: %s (it could block or never end)", kind);
        return -1;
    }
    if ((long long)sb->st_size > max_bytes) {
        snprintf(why, wl, "larger than %lld bytes (%lld)", max_bytes, (long long)sb->st_size);
        return -1;
    }
    return 0;
}

int regfile_open(const char *path, long long max_bytes, char *why, size_t wl)
{
    struct stat sb;
    if (wl)
        why[0] = '\0';
    if (stat(path, &sb) < 0) {
        snprintf(why, wl, "%s", strerror(errno));
        return -1;
    }
    if (judge(&sb, max_bytes, why, wl) < 0)
        return -1;
    /* O_NONBLOCK: if it became a FIFO since the stat, open must not block */
    int fd = open(path, O_RDONLY | O_CLOEXEC | O_NONBLOCK | O_NOCTTY);
    if (fd < 0) {
        snprintf(why, wl, "%s", strerror(errno));
        return -1;
    }
    int fl = fcntl(fd, F_GETFL);
    if (fstat(fd, &sb) < 0 || judge(&sb, max_bytes, why, wl) < 0 || fl < 0 ||
        fcntl(fd, F_SETFL, fl & ~O_NONBLOCK) < 0) {
        if (!why[0])
            snprintf(why, wl, "%s", strerror(errno));
        close(fd);
        return -1;
    }
    return fd;
}

static int owner_set;
static uid_t owner_uid;
static gid_t owner_gid;

void regfile_owner(unsigned uid, unsigned gid)
{
    owner_set = 1;
    owner_uid = (uid_t)uid;
    owner_gid = (gid_t)gid;
}

int regfile_create(const char *path, int flags, unsigned mode)
{
    if (owner_set && (flags & O_CREAT)) {
        int fd = open(path, flags | O_EXCL, (mode_t)mode);
        if (fd >= 0) {
            if (fchown(fd, owner_uid, owner_gid) < 0) { /* (root: cannot fail on a local fs) */
                int e = errno;
                close(fd);
                unlink(path);
                errno = e;
                return -1;
            }
            return fd;
        }
        if (errno != EEXIST)
            return -1;
    }
    return open(path, flags, (mode_t)mode);
}
