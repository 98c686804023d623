// deploy/k8s: the kustomization and its manifests carry what docs/deploy.md promises: one
// coordinator with its own volume behind a Service that routes only to a ready one,
// workers with as many threads as CPUs requested and time to stop cleanly, scaled by KEDA
// on the queue of waiting tiles down to none, and tokens only from the generated Secret.
#include <algorithm>
#include <set>

#include <gtest/gtest.h>

#include "tests/deploy/deploy_yaml.hpp"

namespace tessera {
namespace {

using test::flag_value;
using test::text_of;
using test::texts_of;

const std::string k8s_dir = "deploy/k8s/";

// Every document the kustomization's resources hold.
std::vector<YAML::Node> manifests() {
  std::vector<YAML::Node> all;
  const YAML::Node kustomization = test::load_yaml(k8s_dir + "kustomization.yaml").at(0);
  for (const std::string& file : texts_of(kustomization["resources"]))
    for (const YAML::Node& document : test::load_yaml(k8s_dir + file)) all.push_back(document);
  return all;
}

YAML::Node only(const std::string& kind) {
  const auto found = test::of_kind(manifests(), kind);
  if (found.size() != 1)
    throw std::runtime_error("expected one " + kind + ", found " + std::to_string(found.size()));
  return found.front();
}

YAML::Node pod_spec(const YAML::Node& workload) { return workload["spec"]["template"]["spec"]; }
YAML::Node container(const YAML::Node& workload) { return pod_spec(workload)["containers"][0]; }

// command then args, as the container runs them.
std::vector<std::string> argv_of(const YAML::Node& container) {
  std::vector<std::string> argv = texts_of(container["command"]);
  for (const std::string& arg : texts_of(container["args"])) argv.push_back(arg);
  return argv;
}

// A port given by name or number, as a number of the container's ports (-1: none).
int container_port(const YAML::Node& container, const std::string& port) {
  for (const YAML::Node& entry : container["ports"])
    if (text_of(entry["name"]) == port || text_of(entry["containerPort"]) == port)
      return entry["containerPort"].as<int>();
  return -1;
}

// Kubernetes CPU quantities: "4", "0.5", "500m", in millicores.
int millicores(const std::string& quantity) {
  if (!quantity.empty() && quantity.back() == 'm') return std::stoi(quantity);
  return static_cast<int>(std::stod(quantity) * 1000 + 0.5);
}

// The mount path of the Secret volume named by the pod, with the Secret's name.
std::pair<std::string, std::string> secret_mount(const YAML::Node& workload) {
  for (const YAML::Node& volume : pod_spec(workload)["volumes"]) {
    if (!volume["secret"]) continue;
    for (const YAML::Node& mount : container(workload)["volumeMounts"])
      if (text_of(mount["name"]) == text_of(volume["name"]))
        return {text_of(mount["mountPath"]), text_of(volume["secret"]["secretName"])};
  }
  return {};
}

TEST(DeployYamlTest, EveryYamlFileUnderDeployParses) {
  int files = 0;
  for (const auto& entry :
       std::filesystem::recursive_directory_iterator(test::source_path("deploy"))) {
    const auto extension = entry.path().extension();
    if (extension != ".yaml" && extension != ".yml") continue;
    ++files;
    const std::string relative =
        std::filesystem::relative(entry.path(), TESSERA_SOURCE_DIR).string();
    std::vector<YAML::Node> documents;
    ASSERT_NO_THROW(documents = test::load_yaml(relative)) << relative;
    EXPECT_FALSE(documents.empty()) << relative;
    for (const YAML::Node& document : documents) EXPECT_TRUE(test::is_map(document)) << relative;
  }
  EXPECT_GE(files, 5) << "deploy/compose.yaml and deploy/k8s/*.yaml were not found";
}

TEST(DeployK8sTest, TheKustomizationListsEveryManifestAndGeneratesTheTokens) {
  const YAML::Node kustomization = test::load_yaml(k8s_dir + "kustomization.yaml").at(0);
  EXPECT_EQ(text_of(kustomization["kind"]), "Kustomization");
  const auto resources = texts_of(kustomization["resources"]);
  const std::set<std::string> listed(resources.begin(), resources.end());
  for (const auto& entry : std::filesystem::directory_iterator(test::source_path(k8s_dir))) {
    const std::string name = entry.path().filename().string();
    if (entry.path().extension() == ".yaml" && name != "kustomization.yaml") {
      EXPECT_TRUE(listed.contains(name))
          << k8s_dir << name << " is not in the kustomization's resources";
    }
  }
  for (const std::string& file : resources)
    EXPECT_TRUE(std::filesystem::exists(test::source_path(k8s_dir + file))) << file;

  const YAML::Node generators = kustomization["secretGenerator"];
  ASSERT_TRUE(test::is_sequence(generators) && test::size_of(generators) == 1)
      << "one secretGenerator";
  EXPECT_EQ(text_of(generators[0]["name"]), "tessera-tokens");
  const auto files = texts_of(generators[0]["files"]);
  EXPECT_EQ(std::set<std::string>(files.begin(), files.end()),
            (std::set<std::string>{"api.token", "worker.token", "metrics.token"}));
  // The user makes these files; they must never be committed, nor sent to an image build.
  for (const std::string& file : files) {
    EXPECT_TRUE(test::ignored_by(k8s_dir + ".gitignore", file))
        << file << " is not in deploy/k8s/.gitignore";
    EXPECT_TRUE(test::ignored_by(".dockerignore", k8s_dir + file, true))
        << file << " is not in .dockerignore";
  }
}

TEST(DeployK8sTest, TheCoordinatorIsOneReplicaWithItsOwnVolume) {
  const YAML::Node set = only("StatefulSet");
  // One SQLite database has one writer: a second coordinator must never start.
  EXPECT_EQ(set["spec"]["replicas"].as<int>(0), 1);
  const YAML::Node claims = set["spec"]["volumeClaimTemplates"];
  ASSERT_TRUE(test::is_sequence(claims) && test::size_of(claims) == 1) << "one volumeClaimTemplate";
  const std::string claim = text_of(claims[0]["metadata"]["name"]);
  EXPECT_EQ(texts_of(claims[0]["spec"]["accessModes"]), std::vector<std::string>{"ReadWriteOnce"});
  EXPECT_FALSE(text_of(claims[0]["spec"]["resources"]["requests"]["storage"]).empty());

  const YAML::Node coordinator = container(set);
  const auto argv = argv_of(coordinator);
  ASSERT_FALSE(argv.empty());
  EXPECT_EQ(argv[0], "tessera-server");
  const auto data_dir = flag_value(argv, "--data-dir");
  ASSERT_TRUE(data_dir) << "the coordinator needs --data-dir on its volume";
  bool mounted = false;
  for (const YAML::Node& mount : coordinator["volumeMounts"])
    mounted =
        mounted || (text_of(mount["name"]) == claim && text_of(mount["mountPath"]) == *data_dir);
  EXPECT_TRUE(mounted) << "volume " << claim << " is not mounted at --data-dir " << *data_dir;
  // Workers run in their own pods, scaled apart from the coordinator.
  EXPECT_EQ(flag_value(argv, "--local-workers").value_or(""), "0");
  // The volume is written by the image's user.
  EXPECT_EQ(pod_spec(set)["securityContext"]["fsGroup"].as<int>(0), 10001);
  EXPECT_TRUE(pod_spec(set)["securityContext"]["runAsNonRoot"].as<bool>(false));
}

TEST(DeployK8sTest, TheServiceRoutesToTheCoordinatorsListenPort) {
  const YAML::Node set = only("StatefulSet");
  const YAML::Node service = only("Service");
  EXPECT_EQ(text_of(set["spec"]["serviceName"]), text_of(service["metadata"]["name"]));
  const YAML::Node labels = set["spec"]["template"]["metadata"]["labels"];
  ASSERT_TRUE(test::is_map(service["spec"]["selector"]));
  for (const auto& selector : service["spec"]["selector"])
    EXPECT_EQ(text_of(labels[selector.first.as<std::string>()]), selector.second.as<std::string>())
        << "the Service's selector does not select the coordinator's pods";

  const YAML::Node coordinator = container(set);
  const auto listen = flag_value(argv_of(coordinator), "--listen");
  ASSERT_TRUE(listen) << "the coordinator needs --listen 0.0.0.0:PORT in a pod";
  EXPECT_EQ(listen->substr(0, listen->rfind(':')), "0.0.0.0");
  const int port = test::port_of(*listen);
  EXPECT_EQ(container_port(coordinator, std::to_string(port)), port) << "no containerPort " << port;
  ASSERT_EQ(test::size_of(service["spec"]["ports"]), 1u);
  EXPECT_EQ(container_port(coordinator, text_of(service["spec"]["ports"][0]["targetPort"])), port)
      << "the Service's targetPort is not the port tessera-server listens on";
}

TEST(DeployK8sTest, TheCoordinatorIsProbedOnHealthzAndReadyz) {
  const YAML::Node coordinator = container(only("StatefulSet"));
  const int port = test::port_of(flag_value(argv_of(coordinator), "--listen").value_or(":0"));
  const std::pair<const char*, const char*> probes[] = {
      {"livenessProbe", "/healthz"}, {"readinessProbe", "/readyz"}, {"startupProbe", "/healthz"}};
  for (const auto& [probe, path] : probes) {
    const YAML::Node get = coordinator[probe]["httpGet"];
    ASSERT_TRUE(test::is_map(get)) << probe << " must be an httpGet probe";
    EXPECT_EQ(text_of(get["path"]), path) << probe;
    EXPECT_EQ(container_port(coordinator, text_of(get["port"])), port)
        << probe << " probes another port";
  }
}

TEST(DeployK8sTest, WorkersHaveAsManyThreadsAsCpusRequested) {
  const YAML::Node worker = container(only("Deployment"));
  const auto argv = argv_of(worker);
  ASSERT_FALSE(argv.empty());
  EXPECT_EQ(argv[0], "tessera-worker");
  const auto threads = flag_value(argv, "--threads");
  ASSERT_TRUE(threads)
      << "without --threads a worker takes every core of the node, not its request";
  const std::string cpu = text_of(worker["resources"]["requests"]["cpu"]);
  ASSERT_FALSE(cpu.empty()) << "the worker needs resources.requests.cpu";
  EXPECT_EQ(millicores(cpu), std::stoi(*threads) * 1000)
      << "requests.cpu " << cpu << " does not match --threads " << *threads;
  EXPECT_FALSE(text_of(worker["resources"]["requests"]["memory"]).empty());
}

TEST(DeployK8sTest, WorkersHaveTimeToStopCleanly) {
  const YAML::Node deployment = only("Deployment");
  const int bound = test::worker_shutdown_bound_s();
  EXPECT_GE(pod_spec(deployment)["terminationGracePeriodSeconds"].as<int>(0), bound)
      << "a worker may need " << bound
      << " s after SIGTERM to upload its tile and release the rest";
  // KEDA owns the replica count; a fixed one would be reset by every apply.
  EXPECT_FALSE(deployment["spec"]["replicas"].IsDefined());
}

// The ScaledObject's one trigger (KEDA's), or an undefined node.
YAML::Node trigger_of(const YAML::Node& scaled) {
  const YAML::Node triggers = scaled["spec"]["triggers"];
  return test::size_of(triggers) == 1 ? triggers[0] : YAML::Node(YAML::NodeType::Undefined);
}

TEST(DeployK8sTest, KedaScalesTheWorkersOnTheQueueOfWaitingTiles) {
  const YAML::Node deployment = only("Deployment");
  const YAML::Node scaled = only("ScaledObject");
  EXPECT_EQ(text_of(scaled["apiVersion"]), "keda.sh/v1alpha1");
  const YAML::Node target = scaled["spec"]["scaleTargetRef"];
  EXPECT_EQ(text_of(target["kind"]), "Deployment");
  EXPECT_EQ(text_of(target["apiVersion"]), text_of(deployment["apiVersion"]));
  EXPECT_EQ(text_of(target["name"]), text_of(deployment["metadata"]["name"]));

  ASSERT_EQ(test::size_of(scaled["spec"]["triggers"]), 1u) << "one trigger: the queue depth";
  const YAML::Node trigger = trigger_of(scaled);
  EXPECT_EQ(text_of(trigger["type"]), "prometheus");
  const YAML::Node metadata = trigger["metadata"];
  EXPECT_NE(text_of(metadata["query"]).find("tessera_pending_tiles"), std::string::npos)
      << "the query " << text_of(metadata["query"]) << " does not read the queue depth";
  EXPECT_EQ(text_of(metadata["serverAddress"]).rfind("http", 0), 0u)
      << "serverAddress must be the URL of a Prometheus";
}

TEST(DeployK8sTest, WorkersScaleToZeroAndBackOnTheFirstWaitingTile) {
  const YAML::Node scaled = only("ScaledObject");
  ASSERT_TRUE(scaled["spec"]["minReplicaCount"].IsDefined());
  EXPECT_EQ(scaled["spec"]["minReplicaCount"].as<int>(-1), 0) << "no tile waiting: no worker";
  EXPECT_GT(scaled["spec"]["maxReplicaCount"].as<int>(0), 0);
  // KEDA wakes the Deployment from zero when the query's value exceeds activationThreshold
  // (0 when not given): one waiting tile must do it.
  const std::string activation = text_of(trigger_of(scaled)["metadata"]["activationThreshold"]);
  EXPECT_LT(std::stod(activation.empty() ? "0" : activation), 1.0)
      << "activationThreshold " << activation << ": a single waiting tile would start no worker";
}

TEST(DeployK8sTest, TheLastWorkerOutlastsAStoppingWorkersGracePeriod) {
  const YAML::Node scaled = only("ScaledObject");
  const int grace = pod_spec(only("Deployment"))["terminationGracePeriodSeconds"].as<int>(0);
  ASSERT_TRUE(scaled["spec"]["cooldownPeriod"].IsDefined()) << "say how long the queue waits";
  EXPECT_GT(scaled["spec"]["cooldownPeriod"].as<int>(0), grace)
      << "the queue empties when the last tiles are handed out: the last worker must have "
         "longer than its grace period to render them before it goes";
}

TEST(DeployK8sTest, EachWorkerIsGivenAtLeastATilePerThread) {
  const auto threads = flag_value(argv_of(container(only("Deployment"))), "--threads");
  ASSERT_TRUE(threads);
  const std::string threshold = text_of(trigger_of(only("ScaledObject"))["metadata"]["threshold"]);
  ASSERT_FALSE(threshold.empty()) << "the trigger needs a threshold: tiles waiting per worker";
  EXPECT_GE(std::stod(threshold), std::stod(*threads))
      << "a threshold of " << threshold << " tiles per worker leaves some of its " << *threads
      << " threads idle";
}

TEST(DeployK8sTest, NoAutoscalerOnCpuRemains) {
  // KEDA makes the Deployment's HorizontalPodAutoscaler itself; a second one would fight it.
  EXPECT_TRUE(test::of_kind(manifests(), "HorizontalPodAutoscaler").empty())
      << "a HorizontalPodAutoscaler beside KEDA's ScaledObject";
  for (const YAML::Node& trigger : only("ScaledObject")["spec"]["triggers"])
    EXPECT_NE(text_of(trigger["type"]), "cpu") << "workers scale on the queue, not on CPU use";
}

TEST(DeployK8sTest, TokensComeOnlyFromTheGeneratedSecret) {
  const YAML::Node kustomization = test::load_yaml(k8s_dir + "kustomization.yaml").at(0);
  const std::string secret = text_of(kustomization["secretGenerator"][0]["name"]);
  const auto keys = texts_of(kustomization["secretGenerator"][0]["files"]);
  EXPECT_TRUE(test::of_kind(manifests(), "Secret").empty()) << "a Secret committed with its value";
  const std::pair<const char*, std::vector<const char*>> uses[] = {
      {"StatefulSet", {"--api-token-file", "--worker-token-file", "--metrics-token-file"}},
      {"Deployment", {"--token-file"}}};
  for (const auto& [kind, flags] : uses) {
    const YAML::Node workload = only(kind);
    const auto argv = argv_of(container(workload));
    EXPECT_TRUE(test::token_flags_in(argv).empty()) << kind << " has a token on its command line";
    for (const YAML::Node& variable : container(workload)["env"])
      EXPECT_EQ(text_of(variable["name"]).find("TOKEN"), std::string::npos)
          << kind << ": a token in env";
    const auto [mount, name] = secret_mount(workload);
    EXPECT_EQ(name, secret) << kind << " does not mount the generated Secret";
    // Its files are mode 0440, root's: the image's user reads them through fsGroup.
    EXPECT_EQ(pod_spec(workload)["securityContext"]["fsGroup"].as<int>(0), 10001)
        << kind << " cannot read the Secret's files";
    for (const char* flag : flags) {
      const std::string file = flag_value(argv, flag).value_or("");
      EXPECT_EQ(file.substr(0, mount.size() + 1), mount + "/")
          << kind << " " << flag << " is not in the Secret";
      EXPECT_NE(std::find(keys.begin(), keys.end(), file.substr(file.rfind('/') + 1)), keys.end())
          << kind << " " << flag << " " << file << " is not a key of the Secret";
    }
  }
}

}  // namespace
}  // namespace tessera
