#!/usr/bin/env bash
# The layering rules of docs/architecture.md, checked on the include lines:
# firmware/ includes no OS header and nothing of a HAL implementation; firmware/nav/
# (the core) includes nothing of the application, the CAN layer or the HAL at all;
# the diagnostic transport (firmware/diag/) includes, of the project's headers, only its own
# and hal/hal.h (no application, core or CAN header); the Cortex-M4F drivers
# (hal/cortex_m4f/) and the shared HAL modules (hal/common/) include no OS header either;
# hal/ includes nothing of the application, the core, the CAN layer or the diagnostic
# transport (it is the interface and its drivers: the board entry points that tie the
# application to a HAL live in boards/ and host_sim/).
set -euo pipefail
cd "$(dirname "$0")/.."
fail=0
os_headers='stdio\.h|stdlib\.h|unistd\.h|fcntl\.h|pthread\.h|time\.h|signal\.h|sys/|linux/|net/|errno\.h'
if grep -nE "#include <($os_headers)" firmware/nav/*.[ch] firmware/app/*.[ch] firmware/can/*.[ch] firmware/diag/*.[ch] firmware/boot/*.[ch]; then
    echo "layers: firmware/ includes an OS header (above)"; fail=1
fi
if grep -nE "#include <($os_headers)" hal/cortex_m4f/*.[ch] hal/common/*.[ch]; then
    echo "layers: a Cortex-M4F driver or a shared HAL module includes an OS header (above)"; fail=1
fi
if grep -nE '#include "(hal_linux|fake_hal|hal_stm32|hal_semihost|candump|bxcan|stm32_[a-z]+)\.h"' -r firmware/; then
    echo "layers: firmware/ includes a HAL implementation (above)"; fail=1
fi
if grep -nE '#include "(hal|app|e2e|navecu_can)\.h"' firmware/nav/*.[ch]; then
    echo "layers: the navigation core includes a layer above it (above)"; fail=1
fi
diag_headers=$(cd firmware/diag && ls *.h | sed 's/\./\\./' | paste -sd'|')
if grep -nE '#include "' firmware/diag/*.[ch] | grep -vE "#include \"(hal\\.h|$diag_headers)\""; then
    echo "layers: the diagnostic transport includes a project header other than hal.h (above)"; fail=1
fi
app_headers=$(cd firmware && ls app/*.h nav/*.h can/*.h can/gen/*.h diag/*.h | xargs -n1 basename | sed 's/\./\\./' | paste -sd'|')
if grep -rnE "#include \"($app_headers)\"" hal/; then
    echo "layers: hal/ includes an application, core or CAN header (above): board code belongs in boards/"; fail=1
fi
if grep -nE '#include <($os_headers)' boards/*/*.[ch]; then
    echo "layers: a board of boards/ includes an OS header (above)"; fail=1
fi
# the bootloader's logic (firmware/boot/) sees the diagnostics, the HAL interface and the
# CAN protocol's E2E and codec (its NAV_Heartbeat) only: not the application or the core
boot_ok="hal\\.h|e2e\\.h|navecu_can\\.h|navecu_protocol\\.h|$diag_headers|$(cd firmware/boot && ls *.h | sed 's/\./\\./' | paste -sd'|')"
if grep -nE '#include "' firmware/boot/*.[ch] | grep -vE "#include \"($boot_ok)\""; then
    echo "layers: the bootloader's logic includes a project header other than diag's, the CAN protocol's and hal.h (above)"; fail=1
fi
[ $fail -eq 0 ] && echo "layers: firmware/, hal/ and boards/ respect docs/architecture.md"
exit $fail
