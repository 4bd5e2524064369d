# tapecoil: every target runs inside the provisioned environment (tools/env.sh decides which:
# a host Python with DOLFINx >= 0.9, or a Debian root built on first use).
#   make demo / make test      the two commands of the README
#   make run CMD="..."         any command in the environment
#   TAPECOIL_SUITE=sid make test   the same on Debian sid (DOLFINx 0.11)
ENV := tools/env.sh
RUN := $(ENV) run
NP ?= 2
MESH ?= coarse
CASE ?= fold

.PHONY: setup demo test test-serial test-mpi validate bench lint shell run info clean-env

setup:
	@$(ENV) setup

# the main job: the theory report, then the benchmark pipeline on the coarse mesh (coiling to
# the stowed state, deployment from it, the report with its pictures) on $(NP) ranks
demo: setup
	$(RUN) python3 demos/theory_report.py
	$(RUN) mpirun -n $(NP) python3 demos/benchmark.py $(MESH)

test: setup
	$(RUN) tools/run-tests serial
	$(RUN) tools/run-tests mpi $(NP)

test-serial: setup
	$(RUN) tools/run-tests serial

test-mpi: setup
	$(RUN) tools/run-tests mpi $(NP)

validate: setup
	$(RUN) tools/run-tests slow

bench: setup
	$(RUN) mpirun -n $(NP) python3 tools/bench.py --mesh $(MESH) --case $(CASE)

lint: setup
	$(RUN) ruff check solver tests demos tools
	$(RUN) ruff format --check solver tests demos tools

shell: setup
	@$(ENV) shell

# CMD reaches the recipe through the environment, so quotes inside it survive (as in any make
# argument, a literal dollar is written $$: make run CMD="echo $$HOME").
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
