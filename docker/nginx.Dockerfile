# docker/nginx.Dockerfile — Debian's nginx with docker/nginx.conf, the proxy in front of manipid in
# docker/compose.yaml (profile "proxy"). Its packages come from the [proxy] section of
# scripts/debian-packages.txt through scripts/packages.sh, like the manipid image's.
#
#   docker compose -f docker/compose.yaml --profile proxy up -d --build
ARG BASE=debian:bookworm-slim
FROM ${BASE}
SHELL ["/bin/bash", "-euo", "pipefail", "-c"]
COPY scripts/packages.sh scripts/debian-packages.txt /tmp/manipid-packages/
RUN packages=$(/tmp/manipid-packages/packages.sh proxy); \
    apt-get update -qq; \
    DEBIAN_FRONTEND=noninteractive apt-get install -y -qq --no-install-recommends $packages; \
    apt-get clean; \
    rm -rf /var/lib/apt/lists/* /tmp/manipid-packages; \
    rm -f /etc/nginx/sites-enabled/default
COPY docker/nginx.conf /etc/nginx/nginx.conf
# Fails the image build when the configuration does not parse (manipid's name resolves only
# inside the compose network, so it is checked with a stand-in address).
RUN sed 's/server manipid:8080;/server 127.0.0.1:8080;/' /etc/nginx/nginx.conf >/tmp/check.conf && \
    nginx -t -q -c /tmp/check.conf && rm /tmp/check.conf
EXPOSE 8080
STOPSIGNAL SIGQUIT
HEALTHCHECK --interval=30s --timeout=5s --start-period=10s --retries=3 \
    CMD ["curl", "-fsS", "-o", "/dev/null", "--max-time", "4", "http://127.0.0.1:8080/healthz"]
CMD ["nginx", "-g", "daemon off;"]
