/* Start-up for the emulated Cortex-M7 (QEMU mps2-an500): the vector table, FPU enable, then
 * newlib's _start (rdimon's crt0: stack and heap from semihosting, .bss cleared, constructors,
 * main with the semihosting command line, exit). No interrupts are used. */
  .syntax unified
  .cpu cortex-m7
  .thumb

  .section .vectors, "a"
  .align 2
  .globl __vectors
__vectors:
  .word __stack
  .word Reset_Handler
  .word Fault_Handler   /* NMI */
  .word Fault_Handler   /* HardFault */
  .word Fault_Handler   /* MemManage */
  .word Fault_Handler   /* BusFault */
  .word Fault_Handler   /* UsageFault */
  .word 0, 0, 0, 0      /* reserved */
  .word Fault_Handler   /* SVCall */
  .word Fault_Handler   /* DebugMonitor */
  .word 0               /* reserved */
  .word Fault_Handler   /* PendSV */
  .word Fault_Handler   /* SysTick */

  .text
  .align 2
  .globl Reset_Handler
  .type Reset_Handler, %function
  .thumb_func
Reset_Handler:
  /* Full access to CP10 and CP11 (CPACR bits 20-23): the first floating-point instruction in
   * newlib or the kernels would fault otherwise. */
  ldr r0, =0xE000ED88
  ldr r1, [r0]
  orr r1, r1, #(0xF << 20)
  str r1, [r0]
  dsb
  isb
  b _start
  .size Reset_Handler, . - Reset_Handler

  /* Any exception ends the emulation with a message and a failed status (semihosting
   * SYS_WRITE0, then SYS_EXIT with ADP_Stopped_RunTimeErrorUnknown) instead of hanging. */
  .globl Fault_Handler
  .type Fault_Handler, %function
  .thumb_func
Fault_Handler:
  movs r0, #0x04
  ldr r1, =fault_message
  bkpt 0xab
  movs r0, #0x18
  ldr r1, =0x20023
  bkpt 0xab
  b .
  .size Fault_Handler, . - Fault_Handler

  .section .rodata
fault_message:
  .asciz "FAIL: exception (fault) on the emulated Cortex-M7\n"
