#!/usr/bin/env bash
# Idempotent machine setup for meshletlab on Debian 12 (bookworm), run as root.
#
# Installs only what is missing: Mesa's lavapipe Vulkan driver from bookworm-backports (Mesa >= 24 has
# VK_EXT_mesh_shader; stock bookworm 22.3 does not), the Vulkan loader, shader tools, the validation layer
# and zstd, and python3-venv (without it Debian's python3 has no ensurepip and `python3 -m venv` fails;
# make test's Python step needs a venv, as Debian's Python refuses system-wide pip). The backports source
# reuses the mirror URI that this machine's apt sources already use, so no host name is written here.
# Silent and fast when everything is present.
set -euo pipefail

log() { echo "setup: $*" >&2; }

if ! command -v cargo >/dev/null 2>&1; then
  log "cargo not found: install a Rust toolchain (rustup, stable >= 1.87) first."
  exit 1
fi

# Packages and the minimum version each needs ("" = any). mesa-vulkan-drivers must come from backports.
declare -A MIN_VERSION=(
  [mesa-vulkan-drivers]="24"
  [libvulkan1]=""
  [glslang-tools]=""
  [spirv-tools]=""
  [vulkan-validationlayers]=""
  [zstd]=""
  [python3-venv]=""
)

installed_version() { dpkg-query -W -f='${Status} ${Version}\n' "$1" 2>/dev/null | awk '$3=="installed"{print $4}'; }

missing=()
for pkg in "${!MIN_VERSION[@]}"; do
  have=$(installed_version "$pkg" || true)
  want=${MIN_VERSION[$pkg]}
  if [[ -z "$have" ]]; then
    missing+=("$pkg")
  elif [[ -n "$want" ]] && dpkg --compare-versions "$have" lt "$want"; then
    missing+=("$pkg")
  fi
done
[[ ${#missing[@]} -eq 0 ]] && exit 0

if ! command -v apt-get >/dev/null 2>&1; then
  log "apt-get not found: this script is for Debian 12. Install by hand: ${missing[*]} (see README, 'Other systems')."
  exit 1
fi
if [[ $(id -u) -ne 0 ]]; then
  log "missing packages: ${missing[*]}; run this script as root (or with sudo) to install them."
  exit 1
fi

codename=$(. /etc/os-release && echo "${VERSION_CODENAME:-}")
if [[ "$codename" != "bookworm" ]]; then
  log "this is not Debian 12 (codename '$codename'); install by hand: ${missing[*]} (Mesa >= 24 for mesh shaders)."
  exit 1
fi

# The mirror URI that serves the plain "bookworm" suite, from deb822 (.sources) or one-line (.list) files.
mirror_uri() {
  local f
  for f in /etc/apt/sources.list.d/*.sources; do
    [[ -f "$f" ]] || continue
    awk 'BEGIN{RS=""; IGNORECASE=1}
         /(^|\n)Suites:[^\n]*(^|[ \t])bookworm([ \t\n]|$)/ && /(^|\n)Types:[^\n]*deb([ \t\n]|$)/ {
           if (match($0, /(^|\n)URIs:[ \t]*[^ \t\n]+/)) { s=substr($0,RSTART,RLENGTH); sub(/.*URIs:[ \t]*/, "", s); print s; exit }
         }' "$f"
  done
  for f in /etc/apt/sources.list /etc/apt/sources.list.d/*.list; do
    [[ -f "$f" ]] || continue
    awk '$1=="deb" { i=2; if ($2 ~ /^\[/) { while (i<=NF && $i !~ /\]$/) i++; i++ } if ($(i+1)=="bookworm") { print $i; exit } }' "$f"
  done
}

has_backports() {
  grep -rqsE '(^|[[:space:]])bookworm-backports([[:space:]]|$)' /etc/apt/sources.list /etc/apt/sources.list.d/ 2>/dev/null
}

if ! has_backports; then
  uri=$(mirror_uri | head -n 1)
  if [[ -z "$uri" ]]; then
    log "could not find the Debian mirror for 'bookworm' in /etc/apt/sources*; add bookworm-backports by hand."
    exit 1
  fi
  log "adding bookworm-backports on the configured mirror"
  keyring=/usr/share/keyrings/debian-archive-keyring.gpg
  {
    echo "Types: deb"
    echo "URIs: $uri"
    echo "Suites: bookworm-backports"
    echo "Components: main"
    [[ -f "$keyring" ]] && echo "Signed-By: $keyring"
  } > /etc/apt/sources.list.d/meshletlab-backports.sources
fi

log "installing: ${missing[*]}"
export DEBIAN_FRONTEND=noninteractive
apt-get update -qq >/dev/null
backports=()
plain=()
for pkg in "${missing[@]}"; do
  case "$pkg" in
    mesa-vulkan-drivers) backports+=("$pkg") ;;
    *) plain+=("$pkg") ;;
  esac
done
if [[ ${#backports[@]} -gt 0 ]]; then
  apt-get install -y -qq --no-install-recommends -t bookworm-backports "${backports[@]}" >/dev/null
fi
if [[ ${#plain[@]} -gt 0 ]]; then
  apt-get install -y -qq --no-install-recommends "${plain[@]}" >/dev/null
fi
log "done: $(installed_version mesa-vulkan-drivers | sed 's/^/mesa-vulkan-drivers /')"
