/* host_board.c - the Linux host as a board; see host_board.h. */
#include "host_board.h"

#include <errno.h>
#include <signal.h>
#include <stdio.h>
#include <string.h>

#include "app.h"
#include "hal_linux.h"
#include "hal_socketcan.h"

static volatile sig_atomic_t stop_requested;

static void on_signal(int sig)
{
    (void)sig;
    stop_requested = 1;
}

int host_open(hal_t *hal, const host_options_t *o)
{
    uint32_t ids[HAL_SOCKETCAN_MAX_FILTERS];
    const int rc = o->live_if != NULL
                       ? hal_socketcan_open(hal, o->live_if, ids,
                                            app_uds_rx_ids(&o->cfg, ids, HAL_SOCKETCAN_MAX_FILTERS),
                                            o->out_path, o->nvm_path)
                       : hal_linux_open(hal, o->in_path, o->out_path, o->nvm_path);
    if (rc != 0) {
        const hal_linux_file_t w = hal_linux_open_failed(hal);
        if (w == HAL_LINUX_FILE_NVM_SIZE) {
            fprintf(stderr, "navecu: NVM file '%s' is not an NVM image (%u bytes) or cannot be "
                    "read; refused, left as it is\n", o->nvm_path, HAL_LINUX_NVM_SIZE);
        } else if (w != HAL_LINUX_FILE_NONE) {
            fprintf(stderr, "navecu: cannot %s '%s': %s\n",
                    w == HAL_LINUX_FILE_RX   ? "open the input log"
                    : w == HAL_LINUX_FILE_TX ? "create the output log"
                                             : "open or create the NVM file",
                    w == HAL_LINUX_FILE_RX   ? o->in_path
                    : w == HAL_LINUX_FILE_TX ? o->out_path
                                             : o->nvm_path,
                    strerror(errno));
        } else {
            fprintf(stderr, "navecu: cannot open CAN interface '%s': %s\n",
                    o->live_if != NULL ? o->live_if : "?", strerror(errno));
        }
        return 1;
    }
    if (o->iface != NULL) {
        hal_linux_set_iface(hal, o->iface);
    }
    if (o->live_if != NULL) {
        struct sigaction sa;
        memset(&sa, 0, sizeof sa);
        sa.sa_handler = on_signal;
        sigaction(SIGINT, &sa, NULL);
        sigaction(SIGTERM, &sa, NULL);
        fprintf(stderr, "navecu: running on %s until SIGINT/SIGTERM\n", o->live_if);
    }
    return 0;
}

int host_stop_requested(void)
{
    return stop_requested != 0;
}

int host_wait(hal_t *hal, const host_options_t *o)
{
    if (hal_socketcan_wait(hal, 20) < 0) {
        fprintf(stderr, "navecu: poll failed on %s: %s\n", o->live_if, strerror(errno));
        return -1;
    }
    return 0;
}

int host_poll_allowed(const hal_t *hal, const host_options_t *o, uint64_t t_first_us)
{
    const uint64_t now = hal_time_us(hal);
    return !o->stall_poll || t_first_us == UINT64_MAX || now < t_first_us ||
           now - t_first_us < o->stall_poll_us;
}
