# nginx as the gRPC balancer in front of rdmeshd replicas (docs/ROUTING.md): Debian 12's nginx
# package, with deploy/nginx/rdmesh-grpc.conf. Used by docker/compose.yaml and deploy/k8s/.
#
#   docker build -f docker/nginx.Dockerfile -t rdmesh/nginx .      (from the repository root)
#
# The `server` lines of the config name the replicas; compose mounts the file as it is, and
# Kubernetes replaces it with the ConfigMap in deploy/k8s/nginx.yaml.
FROM debian:bookworm
RUN apt-get update \
 && DEBIAN_FRONTEND=noninteractive apt-get install -y --no-install-recommends nginx \
 && rm -rf /var/lib/apt/lists/* /etc/nginx/sites-enabled/default \
 && ln -sf /dev/stdout /var/log/nginx/access.log \
 && ln -sf /dev/stderr /var/log/nginx/error.log
COPY deploy/nginx/rdmesh-grpc.conf /etc/nginx/conf.d/rdmesh-grpc.conf
EXPOSE 50051
STOPSIGNAL SIGQUIT
CMD ["nginx", "-g", "daemon off;"]
