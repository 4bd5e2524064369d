# tapecoil: every target runs inside the provisioned environment (tools/env.sh decides which:
# a host Python with DOLFINx >= 0.9, or a Debian root built on first use).
#   make demo / make test      the two commands of the README
#   make run CMD="..."         any command in the environment, which sees only the project
#                              directory: a script from elsewhere is copied in first (scratch/)
# The test targets run on each environment of SUITES (tools/test-suites: the serial selections
# side by side, one per core, then the MPI ones in turn), provisioning a missing Debian root
# first, and end with a summary; a failure in any suite fails them:
#   make test                  serial and MPI suites on Debian trixie (DOLFINx 0.9) and sid (0.11)
#   make test SUITES=trixie    one suite only (also: SUITES=sid, SUITES=host for the host Python)
# SUITES defaults to $(TAPECOIL_SUITE) when that is set, to host when TAPECOIL_ENV=host.
# The other targets use the one environment of tools/env.sh (TAPECOIL_SUITE, default trixie).
ENV := tools/env.sh
RUN := $(ENV) run
NP ?= 2
MESH ?= coarse
CASE ?= fold
SUITES ?= $(if $(filter host,$(TAPECOIL_ENV)),host,$(or $(TAPECOIL_SUITE),trixie sid))

.PHONY: setup demo test test-serial test-mpi validate bench lint shell run info clean-env

setup:
	@$(ENV) setup

# the main job: the theory report, then the benchmark pipeline on the coarse mesh (coiling to
# the stowed state, deployment from it, the report with its pictures) on $(NP) ranks
demo: setup
	$(RUN) python3 demos/theory_report.py
	$(RUN) mpirun -n $(NP) python3 demos/benchmark.py $(MESH)

test:
	@NP=$(NP) tools/test-suites "serial mpi" $(SUITES)

test-serial:
	@NP=$(NP) tools/test-suites serial $(SUITES)

test-mpi:
	@NP=$(NP) tools/test-suites mpi $(SUITES)

validate: setup
	$(RUN) tools/run-tests slow

bench: setup
	$(RUN) mpirun -n $(NP) python3 tools/bench.py --mesh $(MESH) --case $(CASE) $(if $(CONFIG),--config $(CONFIG))

lint: setup
	$(RUN) ruff check solver tests demos tools
	$(RUN) ruff format --check solver tests demos tools

shell: setup
	@$(ENV) shell

# CMD reaches the recipe through the environment, so quotes inside it survive (as in any make
# argument, a literal dollar is written $$: make run CMD="echo $$HOME"). Only paths inside the
# project directory are visible in the environment: a command naming a file elsewhere is
# refused, saying so; copy the file into the project (e.g. scratch/, git-ignored) and name it there.
run: export CMD = $(value CMD)
run: setup
	@test -n "$$CMD" || { echo 'usage: make run CMD="tapecoil theory"' >&2; exit 2; }
	@$(RUN) /bin/sh -c "$$CMD"

info:
	@$(ENV) info

# Remove the Debian root. Refuses while anything is mounted inside it.
clean-env:
	@! grep -q " $(CURDIR)/.env/" /proc/mounts || { echo "something is mounted under .env; not removing" >&2; exit 1; }
	rm -rf .env
