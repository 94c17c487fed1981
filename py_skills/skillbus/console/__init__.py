"""`skillbus console`: a web page to watch and drive the robot (docs/console.md).

bus_worker: the thread that owns the bus; live: managers, skills and task trees; world:
the world-model page and its checked edits; server: the FastAPI app; static/: the page.
"""
