#!/bin/sh
# A stand-in for apt-get (tests/test_install_deps.cpp): logs its arguments to $FAKE_APT/calls and
# fails with apt 2.6.1's own messages while $FAKE_APT/COMMAND.held counts attempts left with the
# lock held (update: apt's lists lock; install: dpkg's frontend lock; measured with a lock held
# on scratch copies of those directories), or with $FAKE_APT/COMMAND.error's text.
echo "$*" >>"$FAKE_APT/calls"
for a in "$@"; do case $a in update | install) command=$a ;; esac done
held=$(cat "$FAKE_APT/$command.held" 2>/dev/null || echo 0)
if [ "$held" -gt 0 ]; then
  echo $((held - 1)) >"$FAKE_APT/$command.held"
  if [ "$command" = update ]; then
    echo "E: Could not get lock /var/lib/apt/lists/lock. It is held by process 4242 (apt-get)" >&2
    echo "E: Unable to lock directory /var/lib/apt/lists/" >&2
  else
    echo "E: Could not get lock /var/lib/dpkg/lock-frontend. It is held by process 4242 (apt-get)" >&2
    echo "E: Unable to acquire the dpkg frontend lock (/var/lib/dpkg/lock-frontend), is another process using it?" >&2
  fi
  exit 100
fi
if [ -e "$FAKE_APT/$command.error" ]; then
  cat "$FAKE_APT/$command.error" >&2
  exit 100
fi
exit 0
