/*
 * xstate_preload.c - LD_PRELOAD wrapper around ptrace() that lets Debian 12's
 * user-mode-linux (6.1) boot on hosts whose XSAVE area is larger than UML's
 * buffer (AVX-512, AMX).
 *
 * UML restores the FPU state of its processes with
 * PTRACE_SETREGSET NT_X86_XSTATE and a buffer of a fixed size (2696 bytes in
 * Debian 12's 6.1um4: enough for AVX-512, not for AMX's 8 KiB of tile data;
 * 832 bytes, sizeof(struct _xstate), in older builds).  Host kernels
 * accept only their own full XSAVE size there (arch/x86/kernel/fpu/regset.c,
 * xstateregs_set: count must equal fpu_user_cfg.max_size) and answer EFAULT;
 * the guest panics with "ptrace set fp regs failed, errno = 14".
 *
 * On that EFAULT this wrapper reads the child's full state with
 * PTRACE_GETREGSET, lays UML's bytes over its start and sets the full area:
 * the components UML knows are UML's, the others (AVX-512, AMX) stay as the
 * child has them.  Hosts whose XSAVE area fits are not touched.
 *
 * Environment:
 *   TRAJD_XSTATE_FORCE=1   take the full-size path on every SETREGSET, also
 *                          where the plain call would succeed (so the path is
 *                          exercised on hosts that do not need it)
 *   TRAJD_XSTATE_LOG=FILE  append one line the first time the full-size path
 *                          is taken (sizes, and whether it was forced)
 *
 * Test-only: built by `make` into $(BUILD)/tests/uml/xstate_preload.so and
 * used by tests/uml/host.sh; checked by tests/e2e/test_uml_xstate.sh.
 */
#include <dlfcn.h>
#include <elf.h>
#include <errno.h>
#include <fcntl.h>
#include <stdarg.h>
#include <stdlib.h>
#include <string.h>
#include <sys/ptrace.h>
#include <sys/types.h>
#include <sys/uio.h>
#include <unistd.h>

#ifndef NT_X86_XSTATE
#define NT_X86_XSTATE 0x202
#endif

typedef long (*ptrace_fn)(int, pid_t, void *, void *);

/* The largest XSAVE area of any x86 CPU is about 11 KiB (AMX tile data 8 KiB).
 * Static, not on the stack: UML calls ptrace() on its small kernel stacks, so
 * the path below uses no stack-hungry library calls (no stdio) either; what
 * needs the library (dlsym, getenv, open) is done once at load time.  One
 * host thread of UML traces its processes. */
static unsigned char full_area[64 * 1024] __attribute__((aligned(64)));
static ptrace_fn real_ptrace;
static int forced;
static int log_fd = -1;

__attribute__((constructor)) static void xstate_init(void)
{
    const char *force = getenv("TRAJD_XSTATE_FORCE"), *path = getenv("TRAJD_XSTATE_LOG");
    real_ptrace = (ptrace_fn)dlsym(RTLD_NEXT, "ptrace");
    forced = force && strcmp(force, "1") == 0;
    if (path && *path)
        log_fd = open(path, O_WRONLY | O_CREAT | O_APPEND | O_CLOEXEC, 0644);
}

/* Append the decimal digits of v to *p. */
static void put_num(char **p, unsigned long v)
{
    char digits[24];
    int n = 0;
    do
        digits[n++] = (char)('0' + v % 10);
    while ((v /= 10) && n < (int)sizeof digits);
    while (n)
        *(*p)++ = digits[--n];
}

static void put_str(char **p, const char *s)
{
    while (*s)
        *(*p)++ = *s++;
}

/* One line, the first time the full-size path is taken. */
static void log_once(size_t uml_len, size_t full_len, long rc)
{
    static char line[160];
    char *p = line;
    if (log_fd < 0)
        return;
    put_str(&p, "xstate: full-size SETREGSET ");
    put_num(&p, uml_len);
    put_str(&p, " of ");
    put_num(&p, full_len);
    put_str(&p, forced ? " bytes (forced): " : " bytes: ");
    put_str(&p, rc == 0 ? "ok\n" : "failed\n");
    if (write(log_fd, line, (size_t)(p - line)) < 0) {
        /* nothing more to tell */
    }
    close(log_fd);
    log_fd = -1;
}

/* SETREGSET NT_X86_XSTATE with the child's full area under the caller's bytes. */
static long set_full(pid_t pid, const struct iovec *uml)
{
    struct iovec full = {full_area, sizeof full_area};
    long rc;
    if (real_ptrace(PTRACE_GETREGSET, pid, (void *)(long)NT_X86_XSTATE, &full) < 0)
        return -1;
    /* A buffer at least the host's size (Debian's UML 6.1 has 2696 bytes, enough
     * for AVX-512 but not for AMX) is taken as far as the host's area goes, as
     * the kernel itself truncates it; only forced runs get here with one. */
    memcpy(full_area, uml->iov_base, uml->iov_len < full.iov_len ? uml->iov_len : full.iov_len);
    rc = real_ptrace(PTRACE_SETREGSET, pid, (void *)(long)NT_X86_XSTATE, &full);
    log_once(uml->iov_len, full.iov_len, rc);
    return rc;
}

long ptrace(enum __ptrace_request request, ...)
{
    va_list ap;
    pid_t pid;
    void *addr, *data;
    long rc;

    va_start(ap, request);
    pid = va_arg(ap, pid_t);
    addr = va_arg(ap, void *);
    data = va_arg(ap, void *);
    va_end(ap);
    if (!real_ptrace) {
        errno = ENOSYS;
        return -1;
    }
    if ((int)request != PTRACE_SETREGSET || (long)addr != NT_X86_XSTATE || !data)
        return real_ptrace((int)request, pid, addr, data);
    if (!forced) {
        rc = real_ptrace((int)request, pid, addr, data);
        if (rc == 0 || errno != EFAULT)
            return rc;
    }
    return set_full(pid, (const struct iovec *)data);
}
