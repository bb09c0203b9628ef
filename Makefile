# One way to do each thing. `make demo` and `make test` set themselves up.
PYTHON ?= python3
VENV := .venv
PY := $(VENV)/bin/python
# The data sets' folder; empty: the commands' own default (datasets.DEFAULT_DATA).
DATA ?=
DATA_ARG := $(if $(DATA),--data $(DATA))
STAMP := $(VENV)/.installed
# the interface package (GroundInstruction.srv) built into the venv (tools/build_interfaces.sh)
INTERFACES := $(VENV)/.interfaces
INTERFACE_FILES := $(wildcard interfaces/spatial_grounding_interfaces/*.* \
	interfaces/spatial_grounding_interfaces/srv/*.srv)

.PHONY: setup demo lint test test-fast reproduce reproduce-suite reproduce-ablation reproduce-rl \
	reproduce-shapeworld reproduce-robustness bench clean

setup: $(INTERFACES)

$(STAMP): requirements.txt setup.py
	$(PYTHON) -m venv $(VENV)
	$(PY) -m pip install --quiet --upgrade pip
	$(PY) -m pip install --quiet -r requirements.txt
	$(PY) -m pip install --quiet --no-deps -e .
	touch $(STAMP)

$(INTERFACES): $(STAMP) $(INTERFACE_FILES) tools/build_interfaces.sh tools/fix_ros_wheels.py
	tools/build_interfaces.sh $(VENV)
	touch $(INTERFACES)

demo: $(INTERFACES)
	$(VENV)/bin/spatial-grounding demo --out demo_out

# the ament linters over the package, launch files and tests, as test/test_flake8.py and
# test/test_pep257.py run them
lint: $(INTERFACES)
	$(VENV)/bin/ament_flake8
	$(VENV)/bin/ament_pep257 . test

test: $(INTERFACES)
	ROS_AUTOMATIC_DISCOVERY_RANGE=LOCALHOST $(PY) -m pytest -q test

# the tests marked fast (test/conftest.py's FAST, or @pytest.mark.fast): under a minute on
# 2 cores; `make test` runs them all
test-fast: $(INTERFACES)
	ROS_AUTOMATIC_DISCOVERY_RANGE=LOCALHOST $(PY) -m pytest -q -m fast test

# Every row of the value-map table, trained and evaluated two at a time, one thread each
# (training is deterministic there: the same code gives the same checkpoint, bit for bit):
# results/value_map.json, results/value_map.md, the shipped checkpoints
reproduce: $(INTERFACES)
	$(VENV)/bin/spatial-grounding reproduce $(DATA_ARG) --out results

# The reference suite on the shipped PuddleWorld checkpoints (after `make reproduce`, if it
# changed one): results/suite.*, results/landmarks.*
reproduce-suite: $(INTERFACES)
	$(VENV)/bin/spatial-grounding reproduce --suite-only --out results

# Each change of the clear-references recipe off in turn (about 25 minutes on 2 cores):
# results/ablation.json, results/ablation.md
reproduce-ablation: $(INTERFACES)
	$(VENV)/bin/spatial-grounding reproduce --ablation $(DATA_ARG) --out results

# RL rows of the paper's table (about an hour on 2 cores): results/rl.json, results/rl.md
reproduce-rl: $(INTERFACES)
	$(VENV)/bin/spatial-grounding reproduce-rl $(DATA_ARG) --out results

# ShapeWorld (generated, cached in ~/.cache/spatial_grounding_ros): trains t-VGG and t-RNetAttn
# one after the other, one thread each, ships their checkpoints, evaluates them clean and under
# noise: results/shapeworld.json, results/shapeworld.md, results/shapeworld_noise.md
reproduce-shapeworld: $(INTERFACES)
	$(VENV)/bin/spatial-grounding reproduce-shapeworld --out results

# The robustness study on the shipped checkpoints (t-RNetAttn, t-RNet, t-CNN where shipped;
# about 3 minutes on 2 cores): results/robustness.json, .md, .png; and the
# README's explain figures of the node's default (PW local test examples 6 and 41, and 6
# under noise)
EXPLAIN := $(VENV)/bin/spatial-grounding explain --checkpoint pw_t-rnet-attn --task pw-local $(DATA_ARG)
reproduce-robustness: $(INTERFACES)
	$(VENV)/bin/spatial-grounding reproduce-robustness $(DATA_ARG) --out results
	$(EXPLAIN) --index 6 --out results/explain_success.png
	$(EXPLAIN) --index 41 --out results/explain_failure.png
	$(EXPLAIN) --index 6 --obs-noise 10 --text-noise 3 --out results/explain_noise.png

bench: $(INTERFACES)
	$(VENV)/bin/spatial-grounding bench --out results/bench.json

clean:
	rm -rf $(VENV) build install log demo_out
