"""Constants of the small reference dataset the tests of this directory share."""

# Small on purpose: the whole directory of tests must stay well under a minute and a half.
SAMPLES = 320
SHARD_SIZE = 16
SEED = 5
