//! What happens when the firmware itself fails. A panic drives the safe
//! state first, then logs over defmt and executes `udf`; that and every
//! other fault (bus, memory, usage, a stack overflow) end in the HardFault
//! handler below, which drives the safe state (again) and waits for the
//! independent watchdog (watchdog.rs) to restart the chip within a second;
//! the restarted head reports the watchdog reset (E304) to the host.
//!
//! The handler's entry is assembly that touches no stack: a stack overflow
//! faults below the CCM RAM (memory.x), the core enters HardFault with its
//! frame unwritten and SP below the RAM (CFSR.STKERR), and a handler whose
//! prologue pushed would fault again at priority −1 and lock the core up,
//! every pin as it was (laser on, drivers enabled) until the watchdog bit
//! 0.7–1.9 s later. So the entry writes the safe state with single stores
//! (laser enable and chop low, PA6 taken from TIM3 as a plain output, STEP
//! low, drivers' active-low EN high; the same as [`super::pins::force_safe_state`],
//! which the panic handler calls), moves MSP to a stack of its own and only
//! then branches to Rust. It also drops a lazy FPU context that the fault
//! may have left pending (FPCCR.LSPACT): its save would write to the frame
//! that does not exist at the first FPU instruction. The virtual board
//! (`tests/chip/board`) faults an image mid-measurement with the stack
//! exhausted and times the pins: `board-faults`.
//!
//! The safe state comes before the log: with a probe attached, probe-rs
//! halts the core on the HardFault that `udf` raises, and a log that hung
//! or a halt before the handler must not leave the laser on. The watchdog
//! keeps counting under a debugger's halt (cpu.rs), so a halted head is
//! restarted too.

#[panic_handler]
fn panic(info: &core::panic::PanicInfo) -> ! {
    super::pins::force_safe_state();
    defmt::error!("{}", defmt::Display2Format(info));
    cortex_m::asm::udf()
}

/// The fault handler's own stack (in SRAM, apart from the CCM RAM that may
/// have overflowed); what runs on it calls nothing deep.
#[repr(C, align(8))]
struct FaultStack([u8; FAULT_STACK_BYTES]);

const FAULT_STACK_BYTES: usize = 256;

static mut FAULT_STACK: FaultStack = FaultStack([0; FAULT_STACK_BYTES]);

// `HardFault` is the vector cortex-m-rt's table points at (its linker
// script only PROVIDEs a default). Register addresses from RM0090 §2.3 and
// §8.4, PM0214 §4.6.2: GPIOA 0x4002_0000, GPIOB 0x4002_0400, GPIOC
// 0x4002_0800, BSRR at 0x18, MODER at 0x00; FPCCR 0xE000_EF34.
core::arch::global_asm!(
    ".section .HardFault.safe, \"ax\"",
    ".global HardFault",
    ".type HardFault, %function",
    ".thumb_func",
    "HardFault:",
    // Laser enable (PB0) low.
    "ldr r0, =0x40020418",
    "mov r1, #0x00010000",
    "str r1, [r0]",
    // Chop (PA6) low, then a plain output.
    "ldr r0, =0x40020000",
    "mov r1, #0x00400000",
    "str r1, [r0, #0x18]",
    "ldr r1, [r0]",
    "bic r1, r1, #0x3000",
    "orr r1, r1, #0x1000",
    "str r1, [r0]",
    // STEP (PC0, PC4, PC8) low, EN (PC2, PC6, PC10) high.
    "ldr r0, =0x40020818",
    "ldr r1, =0x01110444",
    "str r1, [r0]",
    // A stack that exists, and no lazy FPU save into the old one.
    "ldr r0, ={stack} + {size}",
    "msr msp, r0",
    "ldr r0, =0xE000EF34",
    "ldr r1, [r0]",
    "bic r1, r1, #1",
    "str r1, [r0]",
    "dsb",
    "b {after}",
    ".ltorg",
    stack = sym FAULT_STACK,
    size = const FAULT_STACK_BYTES,
    after = sym after_fault,
);

/// Past the safe state, on the fault stack: waits for the watchdog. Asleep:
/// at priority −1 no interrupt can wake the core, and the watchdog's reset
/// ends the sleep.
extern "C" fn after_fault() -> ! {
    loop {
        cortex_m::asm::wfi();
    }
}
