"""The editor's HTTP service (FastAPI): projects, uploads, generation jobs, timelines and edits.

``autohaptics.server.app.create_app(settings)`` builds the application; ``autohaptics serve``
runs it with uvicorn. The contract with the browser editor is ``docs/API.md``. This package
imports nothing on its own, so job worker processes load only what they use.
"""
