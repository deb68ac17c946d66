#!/bin/sh
# Make a throw-away test PKI for zendock's TLS profile: a CA, a router certificate for 127.0.0.1 and
# localhost, and one client certificate per service user (its common name is the user's name, which the
# router's access control can match with `cert_common_names` under mutual TLS).
#
#   deploy/zenoh/secure/make_certs.sh [DIR] [CLIENT...]
#
# DIR defaults to deploy/zenoh/secure/certs (git-ignored: keys never go into the repository). CLIENT
# names default to every zendock service user. Files: ca.pem, router.pem/router.key, <client>.pem/.key.
# The CA key is deleted once everything is signed, so nothing more can be issued from this CA.
# These are test certificates: for a real robot, issue certificates from your own CA.
set -eu

DIR=${1:-deploy/zenoh/secure/certs}
[ $# -gt 0 ] && shift
CLIENTS=${*:-simulator battery pose planner docking perception viz ros2_bridge operator viewer}
DAYS=${ZENDOCK_CERT_DAYS:-30}

command -v openssl >/dev/null 2>&1 || { echo "make_certs.sh: openssl not found" >&2; exit 1; }
mkdir -p "$DIR"
umask 077
WORK=$(mktemp -d)
trap 'rm -rf "$WORK"' EXIT

new_key() {
    openssl genpkey -algorithm EC -pkeyopt ec_paramgen_curve:P-256 -out "$1" 2>/dev/null
}

# sign NAME SUBJECT EXTENSIONS: NAME.key and NAME.pem in DIR, signed by the CA
sign() {
    new_key "$DIR/$1.key"
    openssl req -new -key "$DIR/$1.key" -subj "$2" -out "$WORK/$1.csr"
    printf '%b\n' "$3" > "$WORK/$1.ext"
    openssl x509 -req -in "$WORK/$1.csr" -CA "$DIR/ca.pem" -CAkey "$WORK/ca.key" -CAcreateserial \
        -CAserial "$WORK/ca.srl" -days "$DAYS" -sha256 -extfile "$WORK/$1.ext" -out "$DIR/$1.pem" 2>/dev/null
}

new_key "$WORK/ca.key"
openssl req -x509 -new -key "$WORK/ca.key" -subj "/CN=zendock test CA" -days "$DAYS" -sha256 \
    -addext "basicConstraints=critical,CA:TRUE" -addext "keyUsage=critical,keyCertSign,cRLSign" \
    -out "$DIR/ca.pem"

sign router "/CN=router" \
    "basicConstraints=CA:FALSE\nkeyUsage=critical,digitalSignature\nextendedKeyUsage=serverAuth,clientAuth\nsubjectAltName=IP:127.0.0.1,DNS:localhost"
for client in $CLIENTS; do
    sign "$client" "/CN=$client" \
        "basicConstraints=CA:FALSE\nkeyUsage=critical,digitalSignature\nextendedKeyUsage=clientAuth"
done
chmod 644 "$DIR"/*.pem
echo "make_certs.sh: wrote ca.pem, router.pem/.key and certificates for: $CLIENTS (in $DIR, valid $DAYS days)"
