# navecu - top-level build. `make` builds the host firmware core; `make test` builds and
# runs every test twice: plainly and under AddressSanitizer + UBSan. See README.md.

CC ?= cc
BUILD := build

CSTD   := -std=c11
WARN   := -Wall -Wextra -Werror -Wpedantic -Wconversion -Wdouble-promotion -Wfloat-equal \
          -Wshadow -Wstrict-prototypes -Wmissing-prototypes
# -ffp-contract=off on every build: no fused multiply-add, so float32 arithmetic rounds
# the same on the host and the Cortex-M4F (libm trig still differs in the last bits:
# docs/numeric-design.md).
FPFLAGS := -ffp-contract=off -fno-math-errno
CFLAGS_BASE := $(CSTD) -O2 -g $(WARN) $(FPFLAGS)
SAN_FLAGS := -fsanitize=address,undefined -fno-sanitize-recover=all -fno-omit-frame-pointer

CORE_SRC := $(wildcard firmware/nav/*.c)
CORE_INC := -Ifirmware/nav
SUPPORT_SRC_F64 := tests/support/truth.c tests/support/motions.c
SUPPORT_SRC_BOTH := tests/support/nav_run.c
# tests built once per numeric variant (f32 firmware, f64 reference)
TESTS_VARIANT := test_nav_math test_earth test_sins
# tests that link both variants themselves
TESTS_SINGLE := test_drive

.PHONY: all test test-plain test-asan test-cross sim clean help numerics
# keep objects of pattern-built test programs between runs
.SECONDARY:
all: $(BUILD)/host/libnavcore_f32.a $(BUILD)/host/libnavcore_f64.a

help:
	@echo "make          build the navigation core for the host (build/host/)"
	@echo "make test     build and run all unit tests, plain and with ASan+UBSan"
	@echo "make sim      simulate a drive and report accuracy (arrives with issue #4)"
	@echo "make cross    build the core for the Cortex-M4F and check it has no double arithmetic"
	@echo "make numerics measure what compensated float32 accumulation buys (docs/numeric-design.md)"
	@echo "make clean    remove build/"

# $(1) = flavour (host | asan), $(2) = extra flags
define FLAVOUR
$(BUILD)/$(1)/f32/%.o: %.c
	@mkdir -p $$(@D)
	$$(CC) $$(CFLAGS_BASE) $(2) $$(CORE_INC) -Itests/support -MMD -MP -c $$< -o $$@
$(BUILD)/$(1)/f64/%.o: %.c
	@mkdir -p $$(@D)
	$$(CC) $$(CFLAGS_BASE) $(2) -DNAV_REAL_DOUBLE $$(CORE_INC) -Itests/support -MMD -MP -c $$< -o $$@

$(BUILD)/$(1)/libnavcore_f32.a: $(CORE_SRC:%.c=$(BUILD)/$(1)/f32/%.o)
	$$(AR) rcs $$@ $$^
$(BUILD)/$(1)/libnavcore_f64.a: $(CORE_SRC:%.c=$(BUILD)/$(1)/f64/%.o)
	$$(AR) rcs $$@ $$^
$(BUILD)/$(1)/libtestsupport.a: $(SUPPORT_SRC_F64:%.c=$(BUILD)/$(1)/f64/%.o) \
		$(SUPPORT_SRC_BOTH:%.c=$(BUILD)/$(1)/f32/%.o) $(SUPPORT_SRC_BOTH:%.c=$(BUILD)/$(1)/f64/%.o)
	$$(AR) rcs $$@ $$^

$(1)_LIBS := $(BUILD)/$(1)/libtestsupport.a $(BUILD)/$(1)/libnavcore_f32.a $(BUILD)/$(1)/libnavcore_f64.a
$(BUILD)/$(1)/tests/%_f32: $(BUILD)/$(1)/f32/tests/%.o $$($(1)_LIBS)
	@mkdir -p $$(@D)
	$$(CC) $(2) $$^ -lcmocka -lm -o $$@
$(BUILD)/$(1)/tests/%_f64: $(BUILD)/$(1)/f64/tests/%.o $$($(1)_LIBS)
	@mkdir -p $$(@D)
	$$(CC) $(2) $$^ -lcmocka -lm -o $$@
$(BUILD)/$(1)/tests/%: $(BUILD)/$(1)/f64/tests/%.o $$($(1)_LIBS)
	@mkdir -p $$(@D)
	$$(CC) $(2) $$^ -lcmocka -lm -o $$@

$(1)_TEST_BINS := $(foreach t,$(TESTS_VARIANT),$(BUILD)/$(1)/tests/$(t)_f32 $(BUILD)/$(1)/tests/$(t)_f64) \
                  $(foreach t,$(TESTS_SINGLE),$(BUILD)/$(1)/tests/$(t))
endef

$(eval $(call FLAVOUR,host,))
$(eval $(call FLAVOUR,asan,$(SAN_FLAGS)))
$(eval $(call FLAVOUR,plainacc,-DNAV_ACC_PLAIN))

# ---- Cortex-M4F: the same core sources, single-precision FPU, hard float ABI ----
ARM_CC := arm-none-eabi-gcc
ARM_NM := arm-none-eabi-nm
M4_FLAGS := -mcpu=cortex-m4 -mfpu=fpv4-sp-d16 -mfloat-abi=hard -mthumb
$(BUILD)/m4/%.o: %.c
	@mkdir -p $(@D)
	$(ARM_CC) $(CFLAGS_BASE) $(M4_FLAGS) $(CORE_INC) -MMD -MP -c $< -o $@
$(BUILD)/m4/libnavcore.a: $(CORE_SRC:%.c=$(BUILD)/m4/%.o)
	arm-none-eabi-ar rcs $@ $^

# The M4F FPU is single precision: any double operation becomes a libgcc call
# (__aeabi_dadd, __aeabi_f2d, ...). The core must need none.
cross test-cross: $(BUILD)/m4/libnavcore.a
	@if $(ARM_NM) $< | grep -E ' U (__aeabi_(d|f2d|l2d|ul2d|i2d|ui2d)|(sin|cos|tan|sqrt|atan2|asin|acos|atan|fabs|exp|log|pow|floor|ceil)$$)'; then \
	  echo "cross: the Cortex-M4F core uses double-precision arithmetic (above)"; exit 1; fi
	@echo "cross: navigation core built for Cortex-M4F, no double-precision arithmetic"
	@arm-none-eabi-size -t $(CORE_SRC:%.c=$(BUILD)/m4/%.o) | tail -1 | \
	  awk '{print "cross: core code size " $$1 " bytes text, " $$3 " bytes bss"}'

# ---- numerics study: compensated vs plain float32 accumulation ----
numerics: $(BUILD)/host/tests/study_numerics $(BUILD)/plainacc/tests/study_numerics
	@echo "== float32 with compensated accumulation (the firmware)"; $(BUILD)/host/tests/study_numerics
	@echo "== float32 with plain accumulation (-DNAV_ACC_PLAIN)"; $(BUILD)/plainacc/tests/study_numerics

# Each binary's cmocka summary goes to stderr; merge it so CI logs carry it.
define RUN_TESTS
	@fail=0; for t in $(1); do \
	  echo "=== $$t"; \
	  $$t 2>&1 || fail=1; \
	done; \
	if [ $$fail -ne 0 ]; then echo "$(2): SOME TESTS FAILED"; exit 1; fi; \
	echo "$(2): all test programs passed"
endef

test-plain: $(host_TEST_BINS)
	$(call RUN_TESTS,$(host_TEST_BINS),plain build)

test-asan: $(asan_TEST_BINS)
	$(call RUN_TESTS,$(asan_TEST_BINS),ASan+UBSan build)

test: deps
	$(MAKE) test-plain
	$(MAKE) test-asan
	$(MAKE) test-cross

# Install what the tests need when it is missing (CI runs as root on a fresh machine).
.PHONY: deps
deps:
	@./tools/ensure-deps.sh

sim:
	@echo "make sim arrives with the simulator issue (#4): drive simulation, firmware run and"
	@echo "accuracy report are not built yet. 'make test' runs the navigation core's tests."
	@exit 2

clean:
	rm -rf $(BUILD)

-include $(shell find $(BUILD) -name '*.d' 2>/dev/null)
