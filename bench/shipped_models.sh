# Sourced by the benches: `models`, the model files of generated/models.txt generated with their
# full scene, each once, in the file's order.
models=()
while read -r id model scene flags; do
  [[ -z "$id" || "$id" == \#* || "$scene" != full ]] && continue
  [[ " ${models[*]} " == *" $model "* ]] && continue
  models+=("$model")
done < generated/models.txt
