/*
 * boards/qemu/main.c - the navecu application on the Cortex-M4F under QEMU (netduinoplus2,
 * an STM32F405), replaying a candump log through semihosting (hal_semihost.h):
 *
 *   qemu-system-arm -M netduinoplus2 -nographic -monitor none -serial none \
 *       -semihosting-config enable=on,target=native,arg=navecu,arg=IN.log,arg=OUT.log \
 *       [,arg=nvm=NVM.bin] [-icount shift=0 ... arg=TRACE.txt] \
 *       -kernel build/target/navecu-qemu.elf
 *
 * The same main-loop pass as every board (app_loop.h) with the host's log settings (one
 * frame per pass) and the default configuration, so OUT.log equals `build/host/navecu
 * --can-log IN.log --out OUT.log` byte for byte (make target-test). A fourth argument
 * writes the instruction-count trace (bench_trace.h, make target-bench). An argument
 * nvm=FILE (anywhere after OUT.log) backs the NVM with that image file, the host's --nvm
 * format: loaded at start (app_start: defaults, then its parameters), written back at the
 * end (tests/python/test_nvm_qemu.py).
 */
#include <stdint.h>

#include "app.h"
#include "app_loop.h"
#include "bench_trace.h"
#include "hal_semihost.h"
#include "semihost.h"

static hal_t hal;
static app_t app;

void board_main(void) __attribute__((noreturn));
void board_fault(void);

/* an unexpected exception (startup.c's default_handler): fail the run, exit status 3 */
void board_fault(void)
{
    bench_puts("navecu-qemu: fault exception\n");
    semihost_exit(3u);
}

void board_main(void)
{
    const char *all[6];
    const size_t n_all = bench_args(all, 6u);
    /* nvm=FILE taken out; the rest positional */
    const char *argv[5] = {NULL, NULL, NULL, NULL, NULL};
    const char *nvm_path = NULL;
    size_t argc = 0u;
    for (size_t k = 0u; k < n_all; k++) {
        const char *a = all[k];
        if (k >= 3u && a[0] == 'n' && a[1] == 'v' && a[2] == 'm' && a[3] == '=') {
            nvm_path = &a[4];
        } else if (argc < 5u) {
            argv[argc] = a;
            argc++;
        } else {
            /* more than the usage allows: ignored */
        }
    }
    if (argc < 3u || app_init_defaults(&app) != 0) { /* as on the ECU */
        bench_puts("usage: navecu-qemu IN.log OUT.log [TRACE.txt] [nvm=FILE] (semihosting "
                   "arguments)\n");
        semihost_exit(2u);
    }
    if (hal_semihost_open(&hal, argv[1], argv[2]) != 0 ||
        (nvm_path != NULL && hal_semihost_nvm_file(&hal, nvm_path) != 0) ||
        (argc >= 4u && bench_trace_open(argv[3]) != 0)) {
        bench_puts("navecu-qemu: cannot open the input, output, NVM or trace file\n");
        semihost_exit(1u);
    }
    /* the layers: defaults, then the NVM's parameters */
    if (app_start(&app, &hal) != 0) {
        semihost_exit(2u);
    }
    const app_pass_cfg_t one_frame = {1u, 1u};
    uint64_t frames_in = 0u;
    app_pass_t p;
    do {
        const uint32_t updates0 = app_filter_updates(&app);
        p = app_pass(&app, &hal, &one_frame);
        if (p.frames != 0u) {
            frames_in++;
            bench_trace_frame(p.last.id, app_filter_updates(&app) - updates0);
        }
    } while (app_pass_go_on(&p));
    const int close_rc = hal_semihost_close(&hal);
    bench_trace_close();
    if (p.rx_status != HAL_ENODATA) {
        bench_puts("navecu-qemu: read error on the input log\n");
        semihost_exit(1u);
    }
    bench_puts("navecu-qemu: ");
    bench_put_u64(frames_in);
    bench_puts(" frames in, ");
    bench_put_u64(hal_can_rx_lost(&hal));
    bench_puts(" malformed lines skipped, ");
    bench_put_u64(app.keep.tx.frames_sent);
    bench_puts(" frames out, ");
    bench_put_u64(app_samples(&app));
    bench_puts(" IMU samples\n");
    semihost_exit(app.keep.tx.send_errors != 0u || close_rc != 0 ? 1u : 0u);
}
