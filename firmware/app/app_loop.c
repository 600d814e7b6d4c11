/* app_loop.c - one pass of the main loop; see app_loop.h. */
#include "app_loop.h"

#include <string.h>

app_pass_t app_pass(app_t *a, hal_t *hal, const app_pass_cfg_t *cfg)
{
    app_pass_t p;
    memset(&p, 0, sizeof p);
    p.rx_status = HAL_EAGAIN;
    while (p.frames < cfg->max_frames) {
        hal_can_frame_t f;
        p.rx_status = hal_can_receive(hal, &f);
        if (p.rx_status != 0) {
            break;
        }
        app_trace(APP_TRACE_FRAME, 0u);
        app_handle_frame(a, hal, &f);
        if (cfg->poll) {
            app_poll(a, hal);
        }
        app_trace(APP_TRACE_FRAME, 1u);
        p.last = f;
        p.frames++;
    }
    if (!app_pass_go_on(&p)) {
        return p; /* end of input or a device error: the board decides */
    }
    if (p.frames == 0u && cfg->poll) {
        app_poll(a, hal); /* a silent bus: the heartbeat goes on */
    }
    if (app_tasks_ok(a, hal_time_us(hal))) {
        hal_watchdog_kick(hal);
        p.kicked = 1u;
    }
    return p;
}
