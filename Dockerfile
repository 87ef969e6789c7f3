# forming-fenicsx on Debian (bookworm: dolfinx 0.5; trixie: dolfinx 0.9).
#   docker build -t forming-fenicsx .                  # or --build-arg DEBIAN_RELEASE=trixie
#   docker run --rm -v "$PWD/results:/app/results" forming-fenicsx
ARG DEBIAN_RELEASE=bookworm
FROM debian:${DEBIAN_RELEASE}
WORKDIR /app
COPY . /app
RUN scripts/setup && rm -rf /var/lib/apt/lists/*
CMD ["scripts/demo"]
