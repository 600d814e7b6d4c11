/*
 * app_fixture.h - a fresh application on a fresh in-memory HAL (fake_hal.h), the state
 * every test of an application module that takes the whole app_t starts from.
 */
#ifndef NAVECU_TEST_APP_FIXTURE_H
#define NAVECU_TEST_APP_FIXTURE_H

#include "app.h"

/* fake_hal_reset, then app_init with app_default_config(): returns app_init's result. */
int fx_fresh_app(app_t *app, hal_t *hal);

#endif
