"""The project's Python tools (README.md, "The repository"): each is run as a module from
the repository root, `.venv/bin/python -m tools.NAME` (tools.sim.run, tools.kingston.run,
tools.gen_can_doc, ...), and imports the others as `tools.*`; the tests find them through
pytest.ini's pythonpath."""
