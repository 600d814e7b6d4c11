/* app_fixture.c - see app_fixture.h. */
#include "app_fixture.h"

#include "fake_hal.h"

int fx_fresh_app(app_t *app, hal_t *hal)
{
    fake_hal_reset(hal);
    const app_config_t cfg = app_default_config();
    return app_init(app, &cfg);
}
