// ceilposectl keys init | add (SPEC §11): the SROS2-style keystore of a
// secure fleet, made with OpenSSL's library (keystore/).
#include <cstdio>
#include <ctime>
#include <memory>
#include <string>

#include "ctl/command_registry.h"
#include "keystore/keystore.h"
#include "keystore/keystore_layout.h"

namespace ceilpose::ctl {
namespace {

struct KeysArgs {
  std::string dir;
  std::string robot;
  int days = 0;
  bool force = false;
};

void run_keys_init(const KeysArgs& args) {
  if (auto ok = keystore::init_keystore(args.dir, {std::time(nullptr), args.days}); !ok) {
    std::fprintf(stderr, "ceilposectl keys init: %s\n", ok.error().message.c_str());
    return set_exit_code(kExitKeystore);
  }
  const keystore::KeystoreLayout ks{args.dir};
  std::printf(
      "keys init: CA %s (ECDSA P-256, %d days), key %s (mode 0600, keep it off the robots),\n"
      "           governance %s (authenticated, access-controlled, encrypted)\n",
      ks.ca_certificate().c_str(), args.days, ks.ca_private_key().c_str(),
      ks.governance_p7s().c_str());
  set_exit_code(kExitOk);
}

void run_keys_add(const KeysArgs& args) {
  const keystore::EnclaveRequest request{
      .name = args.robot, .validity = {std::time(nullptr), args.days}, .replace = args.force};
  if (auto ok = keystore::add_enclave(args.dir, request); !ok) {
    std::fprintf(stderr, "ceilposectl keys add: %s\n", ok.error().message.c_str());
    return set_exit_code(kExitKeystore);
  }
  const keystore::KeystoreLayout ks{args.dir};
  std::printf(
      "keys add: enclave %s (CN=%s, %d days): publishes rt/%s/*, subscribes to every robot's "
      "pose and status\n",
      ks.enclave_dir(args.robot).c_str(), args.robot.c_str(), args.days, args.robot.c_str());
  set_exit_code(kExitOk);
}

void add_keys_command(CLI::App& app) {
  CLI::App* keys = app.add_subcommand(
      "keys",
      "Make the keystore of a secure fleet (DDS Security, SROS2 layout, SPEC §11): a CA, and an\n"
      "enclave per robot with its key, certificate and signed permissions. Use it with\n"
      "ceilposed --keystore DIR and ceilposectl fleet --keystore DIR --enclave NAME.\n"
      "Exit 0 ok, 2 usage, 6 refused (names the file and the reason).");
  keys->require_subcommand(1);

  auto init = std::make_shared<KeysArgs>();
  CLI::App* init_cmd = keys->add_subcommand(
      "init",
      "Create DIR with a new CA (ECDSA P-256, self-signed) and the signed governance document:\n"
      "no unauthenticated participants, join access control, discovery, liveliness and topic\n"
      "data encrypted. Refuses a DIR that already has a CA.");
  init_cmd->add_option("--keystore", init->dir, "keystore directory")->required();
  init_cmd->add_option("--days", init->days, "validity of the CA, days")
      ->default_val(keystore::kDefaultCaDays)
      ->check(CLI::Range(1, 36500));
  init_cmd->callback([init] { run_keys_init(*init); });

  auto add = std::make_shared<KeysArgs>();
  CLI::App* add_cmd = keys->add_subcommand(
      "add",
      "Create enclave NAME: an ECDSA P-256 key, a certificate CN=NAME signed by the CA, and\n"
      "signed permissions to publish rt/NAME/* and rt/tf and subscribe to rt/*/pose,\n"
      "rt/*/ceilpose_status and rt/*/ceilpose_state (the fleet). NAME is a ROS name (the\n"
      "robot's --robot). An existing enclave\n"
      "is replaced only with --force (rotating the robot's key).");
  add_cmd->add_option("--keystore", add->dir, "keystore directory made by 'keys init'")->required();
  add_cmd->add_option("--robot", add->robot, "robot (enclave) name")->required();
  add_cmd->add_option("--days", add->days, "validity of the certificate and the grant, days")
      ->default_val(keystore::kDefaultEnclaveDays)
      ->check(CLI::Range(1, 36500));
  add_cmd->add_flag("--force", add->force, "replace an existing enclave (new key and certificate)");
  add_cmd->callback([add] { run_keys_add(*add); });
}

const CommandRegistrar kKeysRegistrar{"keys", &add_keys_command};

}  // namespace
}  // namespace ceilpose::ctl
