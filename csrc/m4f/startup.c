/* startup.c - the reset handler and vector table of the Cortex-M4F test programs
 * (make -C csrc test-m4f, bench-m4f) on QEMU's mps2-an386 with semihosting.
 *
 * Reset: enable the FPU (CP10/CP11 full access), zero .bss, open the semihosting
 * console (newlib's librdimon), run main and report its return value to the host as
 * the emulator's exit status (SYS_EXIT_EXTENDED). A fault prints its kind and exits
 * with status 3, so a crash on the target fails the run instead of hanging it. */
#include <stdint.h>
#include <stdio.h>

extern int main(void);
extern void initialise_monitor_handles(void);
extern uint32_t __bss_start__, __bss_end__, __stack_top;

#define SCB_CPACR (*(volatile uint32_t *)0xE000ED88u)
#define SCB_CFSR (*(volatile uint32_t *)0xE000ED28u)

/* semihosting SYS_EXIT_EXTENDED (0x20): ADP_Stopped_ApplicationExit with a status */
static void semihost_exit(int status) __attribute__((noreturn));
static void semihost_exit(int status)
{
    uint32_t block[2] = {0x20026u, (uint32_t)status};
    register uint32_t r0 __asm__("r0") = 0x20u;
    register uint32_t *r1 __asm__("r1") = block;
    __asm__ volatile("bkpt 0xab" : "+r"(r0) : "r"(r1) : "memory");
    for (;;) {
    }
}

/* newlib's exit() ends here (after flushing stdout): report the status */
void _exit(int status)
{
    semihost_exit(status);
}

/* everything after the FPU is on; kept out of line so that no FPU instruction can be
 * scheduled before CPACR is written */
static void __attribute__((noinline)) start(void)
{
    uint32_t *p;
    for (p = &__bss_start__; p < &__bss_end__; ++p) *p = 0;
    initialise_monitor_handles();
    semihost_exit(main() == 0 ? 0 : 1);
}

void Reset_Handler(void)
{
    SCB_CPACR |= 0xFu << 20;
    __asm__ volatile("dsb\n\tisb" ::: "memory");
    start();
}

static void fault(const char *what)
{
    printf("\n%s on the target (CFSR 0x%08lx)\n", what, (unsigned long)SCB_CFSR);
    fflush(stdout);
    semihost_exit(3);
}

static void NMI_Handler(void) { fault("NMI"); }
static void HardFault_Handler(void) { fault("HardFault"); }
static void MemManage_Handler(void) { fault("MemManage fault"); }
static void BusFault_Handler(void) { fault("BusFault"); }
static void UsageFault_Handler(void) { fault("UsageFault"); }
static void Default_Handler(void) { fault("unexpected interrupt"); }

typedef void (*vector)(void);
__attribute__((section(".vectors"), used)) static const vector vectors[16] = {
    (vector)(uintptr_t)&__stack_top, Reset_Handler, NMI_Handler, HardFault_Handler,
    MemManage_Handler, BusFault_Handler, UsageFault_Handler, 0, 0, 0, 0,
    Default_Handler, /* SVCall */
    Default_Handler, /* debug monitor */
    0, Default_Handler, /* PendSV */
    Default_Handler, /* SysTick (the benchmark reads its counter, no interrupt) */
};
