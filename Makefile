# tapecoil: every target runs inside the provisioned environment (tools/env.sh decides which:
# a host Python with DOLFINx >= 0.9, or a Debian root built on first use).
#   make demo / make test      the two commands of the README
#   make docs / docs-check     the documentation site (build/docs) and its check
#   make results MESH=...      rerun the benchmark and regenerate the README's validation table
#   make run CMD="..."         any command in the environment, which sees only the project
#                              directory: a script from elsewhere is copied in first (scratch/)
# The test targets run on each environment of SUITES (tools/test-suites: the serial selections
# side by side, one per core, then the MPI ones in turn), provisioning a missing Debian root
# first, and end with a summary; a failure in any suite fails them:
#   make test                  serial and MPI suites on Debian trixie (DOLFINx 0.9) and sid (0.11),
#                              and the documentation's check once (make docs-check, on trixie)
#   make test SUITES=trixie    one suite only (also: SUITES=sid, SUITES=host for the host Python)
# SUITES defaults to $(TAPECOIL_SUITE) when that is set, to host when TAPECOIL_ENV=host.
# The other targets use the one environment of tools/env.sh (TAPECOIL_SUITE, default trixie).
ENV := tools/env.sh
RUN := $(ENV) run
NP ?= 2
MESH ?= coarse
CASE ?= fold
SUITES ?= $(if $(filter host,$(TAPECOIL_ENV)),host,$(or $(TAPECOIL_SUITE),trixie sid))

.PHONY: setup demo test test-serial test-mpi validate bench lint shell run info clean-env docs docs-check results

setup:
	@$(ENV) setup

# the main job: the theory report, then the benchmark pipeline on the coarse mesh (coiling to
# the stowed state, deployment from it, the report with its pictures) on $(NP) ranks
demo: setup
	$(RUN) python3 demos/theory_report.py
	$(RUN) mpirun -n $(NP) python3 demos/benchmark.py $(MESH)

test:
	@NP=$(NP) tools/test-suites "serial mpi docs" $(SUITES)

test-serial:
	@NP=$(NP) tools/test-suites serial $(SUITES)

test-mpi:
	@NP=$(NP) tools/test-suites mpi $(SUITES)

validate: setup
	$(RUN) tools/run-tests slow

bench: setup
	$(RUN) mpirun -n $(NP) python3 tools/bench.py --mesh $(MESH) --case $(CASE) $(if $(CONFIG),--config $(CONFIG)) $(if $(BASELINE),--baseline $(BASELINE))

# the documentation site, built offline (Sphinx with MyST, from the environment's Debian
# packages) into build/docs: open build/docs/index.html. Every warning is an error.
docs: setup
	$(RUN) env PYTHONPATH=solver python3 -m sphinx -b html -W --keep-going -q docs build/docs
	@echo "the site: build/docs/index.html"

# the site built and checked: internal links and images resolve, a headless browser renders
# the index and a demo page (tools/docs_check.py); make test runs it once, on trixie
docs-check: setup
	$(RUN) tools/docs-check

# run the benchmark pipeline on MESH and keep its summary as docs/results/MESH with the command
# and commit that made it, then rewrite README.md's validation and run-time tables from the
# kept results (tools/validation_table.py; the docs' validation page follows at the next build)
results: setup
	$(RUN) mpirun -n $(NP) python3 -m tapecoil run --mesh $(MESH) --out results/validation-$(MESH) --no-report
	$(RUN) python3 tools/validation_table.py record results/validation-$(MESH) $(MESH) \
	  --command "mpirun -n $(NP) tapecoil run --mesh $(MESH)"

lint: setup
	$(RUN) ruff check solver tests demos tools docs/conf.py
	$(RUN) ruff format --check solver tests demos tools docs/conf.py

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
