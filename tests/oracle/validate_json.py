#!/usr/bin/env python3
"""Validates JSON files against a JSON Schema (python3-jsonschema): validate_json.py SCHEMA FILE...
Exit 0 when every file validates, 1 when one does not (each error printed), 2 on bad input."""
import json
import sys

try:
    import jsonschema
except ImportError:
    print("validate_json.py: python3-jsonschema is not installed (scripts/bootstrap.sh installs it)", file=sys.stderr)
    sys.exit(2)

if len(sys.argv) < 3:
    print(__doc__, file=sys.stderr)
    sys.exit(2)
with open(sys.argv[1]) as f:
    schema = json.load(f)
validator_class = jsonschema.validators.validator_for(schema)
validator_class.check_schema(schema)
validator = validator_class(schema)
bad = 0
for path in sys.argv[2:]:
    with open(path) as f:
        data = json.load(f)
    errors = sorted(validator.iter_errors(data), key=lambda e: list(e.path))
    for e in errors:
        print(f"{path}: {'/'.join(str(p) for p in e.path) or '(root)'}: {e.message}")
    bad += bool(errors)
print(f"validate_json.py: {len(sys.argv) - 2 - bad} of {len(sys.argv) - 2} files valid against {sys.argv[1]}")
sys.exit(1 if bad else 0)
