"""The virtual STM32F405 board the gonio head's unmodified image runs on.

A Cortex-M4F core on the unicorn engine, with what unicorn leaves out of
M-class mode (exceptions, WFE), the chip's memory map and the peripherals
the image programs, modelled from the reference manual RM0090 as register
blocks on a virtual clock of 168 MHz cycles. The head's world behind the
pins (the stages, the laser and the photodiode) is the simulated head's
`board-plant`; a synthetic USB host enumerates the device and bridges its
CDC-ACM port to a pseudo-terminal.

    python3 -m board IMAGE [--seconds S] [--set PB12=1@0.5 ...] [--pty] ...
    python3 -m board.emulate costs IMAGE [NAME]

Modules:

- `board`: the board: the models wired together and the command line
  (`__main__` runs it), its JSON report;
- `emulate`: the ELF loader, the machine on unicorn and its instruction
  counter (`count.c`, built with `cc` at run time); run alone, the
  `gonio-cost` image's costs;
- `core`: the core's exceptions (entry, return, tail-chaining, faults,
  lockup), WFE and SEV, and its runs on the clock;
- `registers`: the core's registers read and written without unicorn's
  per-call dispatch;
- `clock`: the virtual time and the events scheduled on it;
- `bus`: the memory map: the register blocks on unicorn's MMIO pages;
- `nvic`: the NVIC and the SCB's registers;
- `system`: RCC, the flash interface's registers and the independent
  watchdog (IWDG);
- `gpio`: the GPIO ports, SYSCFG's EXTI routing and the EXTI;
- `timer`: the general-purpose timers TIM2–TIM5 (and TIM7);
- `adc`: ADC1, triggered by TIM2, its results through the DMA;
- `dma`: DMA2 stream 0;
- `otg`: the USB OTG_FS core in device mode;
- `usb_host`: the synthetic USB host on its bus;
- `plant`: the `board-plant` process behind the pins.
"""
