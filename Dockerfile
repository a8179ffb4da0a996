# The autohaptics editor and API in one image, installed the way the README does it: Debian
# packages, a virtual environment at /app/.venv and `pip install -e backend` (scripts/setup).
# The checkout stays at /app: the server serves /app/frontend and the virtual chair compiles
# /app/firmware with gcc on first use.
#   docker-compose up -d        (or: docker build -t autohaptics . && docker run -p 127.0.0.1:8000:8000 autohaptics)
FROM debian:bookworm-slim

ENV DEBIAN_FRONTEND=noninteractive \
    PYTHONDONTWRITEBYTECODE=1 \
    PYTHONUNBUFFERED=1 \
    PIP_NO_CACHE_DIR=1 \
    PIP_DISABLE_PIP_VERSION_CHECK=1

# scripts/setup installs python3-venv python3-pip gcc make itself; libc6-dev (C headers, only a
# recommendation of gcc) is needed for the virtual chair on a minimal system.
RUN apt-get update -qq \
 && apt-get install -y -qq --no-install-recommends python3 python3-venv python3-pip gcc make libc6-dev ca-certificates \
 && rm -rf /var/lib/apt/lists/*

WORKDIR /app
# What the Python install needs first (README.md is the package's readme), so edits to the
# frontend or the firmware do not reinstall the dependencies.
COPY README.md ./
COPY scripts/ scripts/
COPY backend/ backend/
RUN scripts/setup && rm -rf /var/lib/apt/lists/*

COPY frontend/ frontend/
COPY firmware/ firmware/
COPY docs/ docs/

# An unprivileged user; in group dialout so a chair's serial port passed with `devices:` opens.
RUN useradd --create-home --uid 1000 --groups dialout autohaptics \
 && mkdir -p /data \
 && chown autohaptics:autohaptics /data
USER autohaptics

ENV PATH=/app/.venv/bin:$PATH \
    AUTOHAPTICS_DATA=/data
VOLUME ["/data"]
EXPOSE 8000
HEALTHCHECK --interval=30s --timeout=5s --start-period=20s --retries=3 \
  CMD ["python", "-c", "import urllib.request; urllib.request.urlopen('http://127.0.0.1:8000/health', timeout=3)"]
# 0.0.0.0 inside the container; publish the port on the host's 127.0.0.1 only (docker-compose.yml).
CMD ["autohaptics", "serve", "--host", "0.0.0.0", "--port", "8000", "--data", "/data"]
