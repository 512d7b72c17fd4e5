#!/usr/bin/env bash
# Makes a throwaway PKI for trying TLS and mutual TLS (tests, benchmarks, a local demo):
#
#   bash deploy/tls/make_test_certs.sh DIR [SERVER_NAMES]
#
# writes into DIR (created; existing files are replaced):
#   ca.crt, ca.key           a self-signed CA (EC P-256, valid 2 days)
#   server.crt, server.key   signed by it; SAN "DNS:localhost,IP:127.0.0.1" or SERVER_NAMES
#                            (an OpenSSL subjectAltName value, e.g. "DNS:localizer.example,IP:10.0.0.5")
#   client.crt, client.key   signed by it, extendedKeyUsage clientAuth (for --tls-client-ca)
#   tokens                   an --auth-token-file with one client and one operator token
#                            (openssl rand), and client.token / operator.token holding each
# Needs the openssl CLI (Debian: openssl). Keys are unencrypted and readable only by the
# owner. For production, use your own CA (or cert-manager in Kubernetes).
set -euo pipefail
dir=${1:?usage: make_test_certs.sh DIR [SERVER_NAMES]}
names=${2:-DNS:localhost,IP:127.0.0.1}
command -v openssl >/dev/null || { echo "make_test_certs.sh: openssl not found (apt-get install openssl)" >&2; exit 1; }
mkdir -p "$dir"
cd "$dir"
umask 077
cat > openssl.cnf <<CNF
[req]
distinguished_name = dn
[dn]
[ca]
basicConstraints = critical,CA:TRUE
keyUsage = critical,keyCertSign,cRLSign
subjectKeyIdentifier = hash
[server]
basicConstraints = CA:FALSE
keyUsage = critical,digitalSignature
extendedKeyUsage = serverAuth
subjectAltName = $names
[client]
basicConstraints = CA:FALSE
keyUsage = critical,digitalSignature
extendedKeyUsage = clientAuth
CNF
key() { openssl genpkey -algorithm EC -pkeyopt ec_paramgen_curve:P-256 -out "$1" 2>/dev/null; }
key ca.key
openssl req -new -x509 -config openssl.cnf -extensions ca -key ca.key -subj "/CN=localizer test CA" \
  -days 2 -out ca.crt
serial=1
for who in server client; do
  key $who.key
  openssl req -new -config openssl.cnf -key $who.key -subj "/CN=localizer test $who" -out $who.csr
  serial=$((serial + 1))
  openssl x509 -req -in $who.csr -CA ca.crt -CAkey ca.key -set_serial $serial -days 2 \
    -extfile openssl.cnf -extensions $who -out $who.crt 2>/dev/null
  rm -f $who.csr
done
openssl rand -hex 32 > client.token
openssl rand -hex 32 > operator.token
{
  echo "# role token (server --auth-token-file; see docs/SECURITY.md)"
  echo "client $(cat client.token)"
  echo "operator $(cat operator.token)"
} > tokens
rm -f openssl.cnf
chmod 0644 ca.crt server.crt client.crt
echo "make_test_certs.sh: CA, server ($names), client certificates and tokens in $dir"
