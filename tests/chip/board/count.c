/* The instruction counter of emulate.py, in C.
 *
 * A Python block hook costs about a microsecond a call: it held the emulator
 * to some 3 M instructions a second, an hour for a full Belcour scan. This
 * hook does the same work in the engine's own thread of execution: for each
 * translated block, add its Thumb-2 instruction count (decoded once per
 * block, cached by address) and follow the stack pointer's lowest value.
 * emulate.py compiles it with the system's `cc` and reads `struct counter`
 * through ctypes; the engine's functions come as pointers from the Python
 * binding, so no unicorn header or library is needed to build it.
 */
#include <stdint.h>

typedef void uc_engine;
typedef int (*reg_read_fn)(uc_engine *uc, int regid, void *value);
typedef int (*mem_read_fn)(uc_engine *uc, uint64_t address, void *bytes, uint64_t size);

/* Shared with emulate.py (`Counter`): keep the layouts equal. */
struct counter {
    uint64_t executed;        /* instructions run so far */
    uint32_t lowest_sp;       /* the deepest the stack went, whole run */
    uint32_t stretch_lowest;  /* the same within the innermost open stretch */
    uint32_t lowest_at;       /* the block that first ran at `lowest_sp` */
    uint32_t pad;
    reg_read_fn reg_read;
    mem_read_fn mem_read;
    int32_t sp_reg;
    int32_t profiling;        /* nonzero: add each block to the profile */
};

/* The profile of one stretch: instructions per block address, an open
 * addressing table of which only the `profile_used` slots are filled. */
#define PROFILE (1u << 16)
uint64_t profile_address[PROFILE];
uint64_t profile_instructions[PROFILE];
uint32_t profile_used[PROFILE];
uint32_t profile_len;

/* Empties the profile (only the slots in use). */
void profile_reset(void) {
    for (uint32_t i = 0; i < profile_len; i++) profile_instructions[profile_used[i]] = 0;
    profile_len = 0;
}

static void profile_add(uint64_t address, uint32_t n) {
    uint32_t slot = (uint32_t)(address >> 1) & (PROFILE - 1);
    for (uint32_t probe = 0; probe < PROFILE; probe++, slot = (slot + 1) & (PROFILE - 1)) {
        if (profile_instructions[slot] == 0) {
            profile_address[slot] = address;
            profile_used[profile_len++] = slot;
        } else if (profile_address[slot] != address) {
            continue;
        }
        profile_instructions[slot] += n;
        return;
    }
}

#define CACHE (1u << 16)
static struct { uint64_t address; uint32_t size, instructions; } cache[CACHE];

/* A 32-bit Thumb-2 instruction starts with a halfword whose top five bits
 * are 0b11101, 0b11110 or 0b11111 (ARMv7-M ARM, A5.1). */
static uint32_t thumb_instructions(const uint8_t *code, uint32_t size) {
    uint32_t n = 0, i = 0;
    while (i + 1 < size) {
        uint32_t top = code[i + 1] >> 3;
        i += (top == 0x1D || top == 0x1E || top == 0x1F) ? 4 : 2;
        n++;
    }
    return n;
}

void count_block(uc_engine *uc, uint64_t address, uint32_t size, void *user) {
    struct counter *c = user;
    uint32_t slot = (uint32_t)(address >> 1) & (CACHE - 1);
    if (cache[slot].address != address || cache[slot].size != size) {
        uint8_t code[4096];
        uint32_t len = size < sizeof code ? size : sizeof code;
        uint32_t n = 0;
        if (c->mem_read(uc, address, code, len) == 0) n = thumb_instructions(code, len);
        cache[slot].address = address;
        cache[slot].size = size;
        cache[slot].instructions = n;
    }
    c->executed += cache[slot].instructions;
    if (c->profiling && cache[slot].instructions) profile_add(address, cache[slot].instructions);
    uint32_t sp = 0;
    c->reg_read(uc, c->sp_reg, &sp);
    if (sp < c->lowest_sp) {
        c->lowest_sp = sp;
        c->lowest_at = (uint32_t)address;
    }
    if (sp < c->stretch_lowest) c->stretch_lowest = sp;
}
