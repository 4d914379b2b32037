/*
 * xstate_check.c - does PTRACE_SETREGSET NT_X86_XSTATE with user-mode-linux's
 * buffer size (832 bytes, sizeof(struct _xstate)) work on this host, and does
 * it keep the traced process's registers right?  Run it plain to see whether
 * the host needs tests/uml/xstate_preload.c, and under that wrapper to check
 * it (tests/e2e/test_uml_xstate.sh).
 *
 * A child loads a pattern into xmm1 (and, where the CPU has AVX-512, into
 * zmm16, which lies beyond those 832 bytes) and stops itself with a raw
 * kill(SIGSTOP) syscall inside one asm block, so no library code touches the
 * registers.  The parent reads the child's state with UML's size, writes a new
 * pattern into xmm1's slot of the legacy area, sets it with UML's size
 * (through ptrace(), i.e. the wrapper when preloaded) and resumes the child,
 * which stores xmm1 and zmm16 as it finds them after the stop.
 *
 * Prints what it saw.  Exit: 0 the set succeeded and the child saw xmm1 as
 * set and zmm16 unchanged; 3 the set failed (errno printed); 1 the set
 * succeeded but a register came back wrong; 2 the check itself failed.
 */
#include <elf.h>
#include <errno.h>
#include <signal.h>
#include <stdint.h>
#include <stdio.h>
#include <string.h>
#include <sys/ptrace.h>
#include <sys/syscall.h>
#include <sys/uio.h>
#include <sys/wait.h>
#include <unistd.h>

#ifndef NT_X86_XSTATE
#define NT_X86_XSTATE 0x202
#endif

#define UML_XSTATE_SIZE 832 /* sizeof(struct _xstate): 512 legacy + 64 header + 256 ymmh */
#define XMM_OFFSET 160      /* xmm0 in the FXSAVE legacy area */
#define XSTATE_BV_OFFSET 512

static const uint8_t xmm_before[16] = {1, 2, 3, 4, 5, 6, 7, 8, 9, 10, 11, 12, 13, 14, 15, 16};
static const uint8_t xmm_set[16] = {0xA5, 0x5A, 0xC3, 0x3C, 0x11, 0x22, 0x33, 0x44,
                                    0x55, 0x66, 0x77, 0x88, 0x99, 0xAA, 0xBB, 0xCC};

static int have_avx512(void)
{
    __builtin_cpu_init();
    return __builtin_cpu_supports("avx512f");
}

/* The child: registers in, stop, registers out, verdict as exit status. */
static int child(int avx512)
{
    uint8_t xmm_out[16];
    uint8_t zmm_in[64], zmm_out[64];
    long pid = getpid();
    for (int i = 0; i < 64; i++)
        zmm_in[i] = (uint8_t)(0x40 + i);
    memset(zmm_out, 0, sizeof zmm_out);
    if (ptrace(PTRACE_TRACEME, 0, NULL, NULL) < 0)
        return 2;
    if (avx512)
        __asm__ volatile("vmovdqu64 (%[z]), %%zmm16\n\t"
                         "movdqu (%[a]), %%xmm1\n\t"
                         "syscall\n\t"
                         "movdqu %%xmm1, (%[o])\n\t"
                         "vmovdqu64 %%zmm16, (%[zo])\n\t"
                         :
                         : "a"((long)SYS_kill), "D"(pid), "S"((long)SIGSTOP), [a] "r"(xmm_before),
                           [o] "r"(xmm_out), [z] "r"(zmm_in), [zo] "r"(zmm_out)
                         : "rcx", "r11", "xmm1", "memory");
    else
        __asm__ volatile("movdqu (%[a]), %%xmm1\n\t"
                         "syscall\n\t"
                         "movdqu %%xmm1, (%[o])\n\t"
                         :
                         : "a"((long)SYS_kill), "D"(pid),
                           "S"((long)SIGSTOP), [a] "r"(xmm_before), [o] "r"(xmm_out)
                         : "rcx", "r11", "xmm1", "memory");
    if (memcmp(xmm_out, xmm_set, 16) != 0)
        return 1;
    if (avx512 && memcmp(zmm_out, zmm_in, 64) != 0)
        return 1;
    return 0;
}

int main(void)
{
    int avx512 = have_avx512(), st, set_errno = 0;
    uint8_t area[UML_XSTATE_SIZE];
    struct iovec iov = {area, sizeof area};
    long rc;
    pid_t pid = fork();
    if (pid < 0)
        return 2;
    if (pid == 0)
        _exit(child(avx512));
    if (waitpid(pid, &st, 0) != pid || !WIFSTOPPED(st)) {
        fprintf(stderr, "xstate_check: the child did not stop\n");
        return 2;
    }
    if (ptrace(PTRACE_GETREGSET, pid, (void *)(long)NT_X86_XSTATE, &iov) < 0) {
        fprintf(stderr, "xstate_check: GETREGSET: %s\n", strerror(errno));
        kill(pid, SIGKILL);
        return 2;
    }
    memcpy(area + XMM_OFFSET + 16, xmm_set, 16);
    area[XSTATE_BV_OFFSET] |= 2; /* SSE state present */
    iov.iov_len = sizeof area;
    rc = ptrace(PTRACE_SETREGSET, pid, (void *)(long)NT_X86_XSTATE, &iov);
    if (rc < 0)
        set_errno = errno;
    printf("xstate_check: avx512 %s; SETREGSET of %d bytes: %s\n", avx512 ? "yes" : "no",
           UML_XSTATE_SIZE, rc < 0 ? strerror(set_errno) : "ok");
    if (ptrace(PTRACE_CONT, pid, NULL, NULL) < 0 || waitpid(pid, &st, 0) != pid || !WIFEXITED(st)) {
        fprintf(stderr, "xstate_check: the child did not exit\n");
        kill(pid, SIGKILL);
        return 2;
    }
    if (rc < 0)
        return set_errno == EFAULT ? 3 : 2;
    printf("xstate_check: child saw xmm1 %s%s\n", WEXITSTATUS(st) == 0 ? "as set" : "WRONG",
           avx512 ? (WEXITSTATUS(st) == 0 ? ", zmm16 kept" : " or zmm16 lost") : "");
    return WEXITSTATUS(st) == 0 ? 0 : 1;
}
