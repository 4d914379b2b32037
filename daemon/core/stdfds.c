/* stdfds.c - fds 0..2 never left closed (see stdfds.h). */
#include "stdfds.h"

#include <errno.h>
#include <fcntl.h>
#include <unistd.h>

int stdfds_open(void)
{
    for (int fd = 0; fd <= 2; fd++) {
        if (fcntl(fd, F_GETFD) >= 0 || errno != EBADF)
            continue;
        /* the lowest free fd: this one, since the lower ones are open now */
        int n = open("/dev/null", fd ? O_WRONLY : O_RDONLY);
        if (n < 0)
            return -errno;
        if (n != fd) { /* cannot happen, but never leave it elsewhere */
            int rc = dup2(n, fd) < 0 ? -errno : 0;
            close(n);
            if (rc < 0)
                return rc;
        }
    }
    return 0;
}
