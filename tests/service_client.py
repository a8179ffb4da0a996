"""The web service as a local program reaches it in tests: Host 127.0.0.1:8000 (a name the service
answers to, docs/API.md "Security") and the session token from ``GET /api/session`` kept as a cookie."""

from __future__ import annotations

from fastapi.testclient import TestClient

BASE_URL = "http://127.0.0.1:8000"


class LocalClient(TestClient):
    """``TestClient`` for ``app`` at :data:`BASE_URL`; entering it starts the app and takes the token."""

    def __init__(self, app, **kwargs):
        super().__init__(app, base_url=BASE_URL, **kwargs)

    def __enter__(self) -> "LocalClient":
        client = super().__enter__()
        response = client.get("/api/session")
        assert response.status_code == 200, response.text
        return client
