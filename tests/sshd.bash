# shellcheck shell=bash
# A private sshd on 127.0.0.1 for tests/ssh.sh and bench/ssh.sh, so that
# remote workers are tested over real ssh without touching the user's
# ~/.ssh or the machine's sshd. Source it after lib.sh (it uses $T).
#
#   start_sshd [EXTRA_CONFIG_LINE...]
#     starts sshd at a free port with its own host key, one authorized
#     key (for the user running the test) and its own settings (no PAM,
#     StrictModes off, TMPDIR=$T/remote and HOME=$T/remote-home for the
#     sessions); sets
#     SSHD_PORT, SSHD_PID, SSH_HOME (a HOME whose .ssh has the user key,
#     a known_hosts with the host key, and nothing else) and REMOTE_TMP.
#     Returns 1 with SSHD_WHY set when sshd cannot be started.
#   stop_sshd
#   rad_ssh ARGS...   the master with HOME=$SSH_HOME and no ssh agent

start_sshd() {
  local sshd=/usr/sbin/sshd d=$T/sshd port try i
  SSHD_WHY=""
  if [ ! -x "$sshd" ]; then SSHD_WHY="no $sshd (apt-get install openssh-server)"; return 1; fi
  if ! command -v ssh-keygen >/dev/null; then SSHD_WHY="no ssh-keygen (openssh-client)"; return 1; fi
  mkdir -p "$d/keys" "$T/home/.ssh" "$T/remote" "$T/remote-home"
  chmod 700 "$T/home/.ssh"
  # Keys are kept across a restart (another config, same identities).
  [ -f "$d/host_key" ] || ssh-keygen -q -t ed25519 -N '' -C test-host -f "$d/host_key" ||
    { SSHD_WHY="ssh-keygen failed"; return 1; }
  [ -f "$T/home/.ssh/id_ed25519" ] || ssh-keygen -q -t ed25519 -N '' -C test-user -f "$T/home/.ssh/id_ed25519" ||
    { SSHD_WHY="ssh-keygen failed"; return 1; }
  cp "$T/home/.ssh/id_ed25519.pub" "$d/keys/$(id -un)"
  # sshd checks for its privilege separation directory even when unused.
  [ -d /run/sshd ] || mkdir -p /run/sshd 2>/dev/null
  REMOTE_TMP=$T/remote
  for try in 1 2 3 4 5; do
    port=$(( 20000 + (RANDOM * 32768 + RANDOM) % 40000 ))
    {
      echo "Port $port"
      echo "ListenAddress 127.0.0.1"
      echo "HostKey $d/host_key"
      echo "PidFile $d/sshd.pid"
      echo "AuthorizedKeysFile $d/keys/%u"
      echo "StrictModes no"
      echo "UsePAM no"
      echo "PasswordAuthentication no"
      echo "KbdInteractiveAuthentication no"
      echo "PermitRootLogin prohibit-password"
      # The sessions' HOME too: no login shell start-up files of the
      # machine's user (slow ones would only slow the tests down).
      echo "SetEnv TMPDIR=$REMOTE_TMP HOME=$T/remote-home"
      echo "LogLevel VERBOSE"
      local line
      for line in "$@"; do echo "$line"; done
    } >"$d/config"
    "$sshd" -D -e -f "$d/config" 2>>"$d/log" &
    SSHD_PID=$!
    for i in $(seq 50); do
      if (exec 3<>"/dev/tcp/127.0.0.1/$port") 2>/dev/null; then
        SSHD_PORT=$port
        echo "[127.0.0.1]:$port $(cat "$d/host_key.pub")" >"$T/home/.ssh/known_hosts"
        return 0
      fi
      kill -0 "$SSHD_PID" 2>/dev/null || break
      sleep 0.1
    done
    kill "$SSHD_PID" 2>/dev/null; wait "$SSHD_PID" 2>/dev/null
  done
  SSHD_WHY="sshd would not start: $(tail -3 "$d/log" | tr '\n' ' ')"
  return 1
}

stop_sshd() {
  [ -n "${SSHD_PID:-}" ] || return 0
  kill "$SSHD_PID" 2>/dev/null
  wait "$SSHD_PID" 2>/dev/null
  SSHD_PID=""
}

rad_ssh() { env -u SSH_AUTH_SOCK HOME="$SSH_HOME" "$RADIOSITY" "$@"; }
