#!/usr/bin/env bash
# Make a Debian bookworm base image for zendock without any image registry (debootstrap, then podman import),
# for machines that reach Debian's package mirror but no registry. Idempotent: an existing image is kept.
#
#   deploy/docker/base-image.sh [IMAGE_NAME]        (default zendock-base:bookworm; needs root)
#
# The base has ca-certificates and the machine's own extra CA certificates (a TLS-inspecting proxy's, from
# /usr/local/share/ca-certificates), so pip inside a build trusts what the host trusts. Python itself is
# installed by the Dockerfile, which does so whenever its base lacks it.
set -euo pipefail

IMAGE="${1:-zendock-base:bookworm}"
ENGINE="${CONTAINER_ENGINE:-podman}"

if "$ENGINE" image exists "$IMAGE" 2>/dev/null; then
    echo "base image $IMAGE: already there"
    exit 0
fi

# The machine's own Debian mirror (deb822 or one-line apt sources), else Debian's.
mirror=$(grep -hoE '^URIs: *\S+' /etc/apt/sources.list.d/*.sources 2>/dev/null | awk '{print $2}' \
         | grep -v security | head -1 || true)
if [ -z "$mirror" ]; then
    mirror=$(grep -hoE '^deb +(\[[^]]*\] +)?\S+' /etc/apt/sources.list 2>/dev/null | awk '{print $NF}' \
             | grep -v security | head -1 || true)
fi
mirror="${mirror:-http://deb.debian.org/debian}"

root=$(mktemp -d /tmp/zendock-base.XXXXXX)
trap 'rm -rf "$root"' EXIT
echo "base image $IMAGE: debootstrap bookworm from $mirror"
debootstrap --variant=minbase --include=ca-certificates bookworm "$root" "$mirror" > "$root.log" 2>&1 \
    || { tail -20 "$root.log" >&2; echo "debootstrap failed (log above)" >&2; exit 1; }
rm -f "$root.log"
if compgen -G "/usr/local/share/ca-certificates/*.crt" > /dev/null; then
    cp /usr/local/share/ca-certificates/*.crt "$root/usr/local/share/ca-certificates/"
    chroot "$root" update-ca-certificates > /dev/null
fi
# A smaller base: no apt lists or caches (the Dockerfile updates the lists when it installs anything), and no
# manuals, documentation or translations, now or from packages installed later (dpkg leaves them out).
rm -rf "$root"/var/lib/apt/lists/* "$root"/var/cache/apt/*.bin "$root"/var/cache/apt/archives/*.deb
cat > "$root/etc/dpkg/dpkg.cfg.d/01-zendock-nodoc" <<'NODOC'
path-exclude=/usr/share/doc/*
path-include=/usr/share/doc/*/copyright
path-exclude=/usr/share/man/*
path-exclude=/usr/share/info/*
path-exclude=/usr/share/locale/*
path-include=/usr/share/locale/locale.alias
NODOC
find "$root/usr/share/doc" -mindepth 1 -not -name copyright -not -type d -delete 2>/dev/null || true
rm -rf "$root"/usr/share/man/* "$root"/usr/share/info/*
find "$root/usr/share/locale" -mindepth 1 -maxdepth 1 -not -name locale.alias -exec rm -rf {} + 2>/dev/null || true
tar -C "$root" -c . | "$ENGINE" import --change 'CMD ["/bin/bash"]' - "$IMAGE" > /dev/null
echo "base image $IMAGE: made ($("$ENGINE" image inspect --format '{{.Size}}' "$IMAGE" | awk '{printf "%.0f MB", $1/1e6}'))"
