/* csv_tail.c - the field count of a CSV file's last line (see csv_tail.h). */
#include "csv_tail.h"

#include <fcntl.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

int csv_tail_fields(const char *path)
{
    char buf[CSV_TAIL_BYTES + 1];
    int fd = open(path, O_RDONLY | O_CLOEXEC | O_NONBLOCK);
    if (fd < 0)
        return 0;
    struct stat sb;
    ssize_t n = -1;
    if (fstat(fd, &sb) == 0 && S_ISREG(sb.st_mode)) {
        off_t at = sb.st_size > CSV_TAIL_BYTES ? sb.st_size - CSV_TAIL_BYTES : 0;
        n = pread(fd, buf, CSV_TAIL_BYTES, at);
    }
    close(fd);
    if (n <= 0)
        return 0;
    buf[n] = '\0';
    /* lines from the end: [b, e) without its newline; the first may be cut */
    size_t e = (size_t)n;
    while (e > 0) {
        size_t b = e;
        while (b > 0 && buf[b - 1] != '\n')
            b--;
        if (b == 0 && (size_t)n == CSV_TAIL_BYTES)
            return 0; /* reached the start of a window that cut a line */
        if (e > b && buf[b] != '#' && buf[b] != '\r') {
            int fields = 1;
            for (size_t i = b; i < e; i++)
                fields += buf[i] == ',';
            return fields;
        }
        e = b ? b - 1 : 0;
    }
    return 0;
}
