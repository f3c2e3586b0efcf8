# pointdagd in a Debian 12 image (docs: README "Docker"). Build: scripts/container-image (it makes the
# Debian 12 base from Debian's own mirror with mmdebstrap and builds with podman); any Debian 12 base
# works: --build-arg BASE=debian:12.
ARG BASE=localhost/pointdag-base:bookworm

# ---- build: the same scripts/setup as CI, then the daemon, the CLI and the web viewer ----
FROM ${BASE} AS build
ENV DEBIAN_FRONTEND=noninteractive
# scripts/setup expects Node.js and npm (CI machines have Node 20); Debian's own serve the bundler.
RUN apt-get update -q && apt-get install -y -q --no-install-recommends nodejs npm ca-certificates
WORKDIR /src
COPY scripts/setup scripts/setup
COPY web/package.json web/package-lock.json web/
# npm fetches over TLS: the host's CA bundle (scripts/container-image passes it as the secret
# host_cas) lets that work behind a TLS-inspecting proxy; it is not kept in any layer.
RUN --mount=type=secret,id=host_cas,target=/run/secrets/host_cas \
    npm_config_cafile=/run/secrets/host_cas scripts/setup
COPY . .
RUN cmake -S . -B /build -G Ninja -DCMAKE_BUILD_TYPE=RelWithDebInfo -DPOINTDAG_BUILD_TESTS=OFF \
 && cmake --build /build \
 && install -D -m 0755 /build/server/pointdagd /out/usr/local/bin/pointdagd \
 && install -D -m 0755 /build/tools/pointdag /out/usr/local/bin/pointdag \
 && install -D -m 0644 /build/codec/libpointdag_pcl_reader.so /out/usr/local/lib/pointdag/libpointdag_pcl_reader.so \
 && mkdir -p /out/usr/local/share/pointdag/web \
 && cp -r /build/web/index.html /build/web/assets /out/usr/local/share/pointdag/web/ \
 && install -D -m 0644 configs/container.toml /out/etc/pointdag/pointdagd.toml

# ---- runtime: the shared libraries the two binaries load, nothing to build with ----
FROM ${BASE}
ENV DEBIAN_FRONTEND=noninteractive
RUN apt-get update -q && apt-get install -y -q --no-install-recommends \
      libastcenc3d libboost-filesystem1.74.0 libboost-iostreams1.74.0 libdraco7 libfmt9 libgeographiclib23 \
      libgomp1 libmeshoptimizer2d libpcl-common1.13 libpcl-io1.13 libpng16-16 libproj25 proj-data \
      libspdlog1.10 libsqlite3-0 libssl3 libtbb12 libtomlplusplus3 libturbojpeg0 libvulkan1 \
      mesa-vulkan-drivers libwebp7 libxxhash0 libzstd1 curl ca-certificates \
 && rm -rf /var/lib/apt/lists/* \
 && useradd --system --home-dir /var/lib/pointdag --create-home --shell /usr/sbin/nologin pointdag
COPY --from=build /out/ /
USER pointdag
VOLUME /var/lib/pointdag
EXPOSE 8080
# Configuration: /etc/pointdag/pointdagd.toml (mount your own over it), flags after the image name,
# the token from POINTDAGD_TOKEN or a file (--token-file /run/secrets/pointdag_token); none is baked in,
# and without one the daemon refuses to listen beyond loopback.
ENV XDG_CACHE_HOME=/var/lib/pointdag/cache
HEALTHCHECK --interval=10s --timeout=3s --start-period=30s --retries=3 \
  CMD curl -fsS http://127.0.0.1:8080/readyz || exit 1
STOPSIGNAL SIGTERM
ENTRYPOINT ["/usr/local/bin/pointdagd", "--config", "/etc/pointdag/pointdagd.toml"]
